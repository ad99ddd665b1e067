#pragma once
// The report page: web/report.html with the charting libraries, web/report.js and
// web/report.css inlined, so the page needs no network. The static report carries its data
// inline; the live page fetches it from the coordinator's HTTP API and polls.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

namespace demcal::report {

/// report.html of `demcal report`: `data` is report_data()'s document.
std::string static_report_html(const nlohmann::json& data);

/// The live page of one campaign: polls `api` (a path on the same server) every
/// `interval_ms` and redraws when the data changed. The bearer token, if any, is read from
/// the page's fragment (#token=...), which the browser never sends to the server.
std::string live_report_html(std::int64_t id, const std::string& api, int interval_ms);

/// The live index: the campaigns the coordinator holds, each linking to its live page.
std::string live_index_html(const std::string& api);

/// JSON made safe inside a <script> element: every '<' written as \u003c.
std::string script_safe_json(const nlohmann::json& j);

}  // namespace demcal::report
