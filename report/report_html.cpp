#include "report/report_html.hpp"

#include <map>
#include <stdexcept>
#include <string_view>

namespace demcal::report {
namespace assets {
extern const std::string_view vega_js, vega_lite_js, vega_embed_js, report_js, report_css,
    report_html;
}  // namespace assets

namespace {

using nlohmann::json;

/// Replaces each @NAME@ of the template by its value in one pass over the template only, so a
/// marker-like text inside an inlined library is never touched.
std::string fill(std::string_view templ, const std::map<std::string, std::string_view>& values) {
  std::string out;
  out.reserve(templ.size() + 1'200'000);
  std::size_t pos = 0;
  while (pos < templ.size()) {
    const std::size_t at = templ.find('@', pos);
    if (at == std::string_view::npos) break;
    const std::size_t end = templ.find('@', at + 1);
    if (end == std::string_view::npos) break;
    const auto it = values.find(std::string(templ.substr(at + 1, end - at - 1)));
    if (it == values.end()) {
      out.append(templ.substr(pos, at + 1 - pos));
      pos = at + 1;
      continue;
    }
    out.append(templ.substr(pos, at - pos));
    out.append(it->second);
    pos = end + 1;
  }
  out.append(templ.substr(pos));
  return out;
}

std::string html_escape(const std::string& s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string page(const std::string& title, const json& page_options, const std::string& data) {
  const std::string options = script_safe_json(page_options);
  return fill(assets::report_html, {{"TITLE", html_escape(title)},
                                    {"CSS", assets::report_css},
                                    {"VEGA", assets::vega_js},
                                    {"VEGA_LITE", assets::vega_lite_js},
                                    {"VEGA_EMBED", assets::vega_embed_js},
                                    {"VEGA_LITE_VERSION", DEMCAL_VEGA_LITE_VERSION},
                                    {"PAGE", options},
                                    {"DATA", data},
                                    {"REPORT_JS", assets::report_js}});
}

}  // namespace

std::string script_safe_json(const json& j) {
  const std::string s = j.dump(-1, ' ', false, json::error_handler_t::replace);
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    if (c == '<')
      out += "\\u003c";
    else
      out += c;
  }
  return out;
}

std::string static_report_html(const json& data) {
  const std::string title = "demcal report: campaign " + std::to_string(data.value("id", 0)) + " " +
                            data["campaign"].value("name", "");
  return page(title, {{"mode", "static"}}, script_safe_json(data));
}

std::string live_report_html(std::int64_t id, const std::string& api, int interval_ms) {
  return page("demcal live: campaign " + std::to_string(id),
              {{"mode", "live"}, {"id", id}, {"api", api}, {"interval", interval_ms}}, "null");
}

std::string live_index_html(const std::string& api) {
  return page("demcal live: campaigns", {{"mode", "index"}, {"api", api}, {"interval", 5000}},
              "null");
}

}  // namespace demcal::report
