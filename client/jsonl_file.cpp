#include "client/jsonl_file.hpp"

#include <zlib.h>

#include <fstream>
#include <iostream>
#include <stdexcept>

#include "core/common/error.hpp"

namespace demcal::cli {
namespace {

struct Contents {
  std::vector<std::string> lines;
  bool cut = false;  ///< a gzip file that ends inside a member (its writer was killed)
};

/// The file's lines, through zlib, which reads plain text as it is.
Contents read_lines(const std::filesystem::path& path) {
  gzFile in = gzopen(path.c_str(), "rb");
  if (!in) throw InputError(path.string(), "cannot be opened");
  std::string text;
  char buffer[1 << 16];
  int n = 0;
  while ((n = gzread(in, buffer, sizeof buffer)) > 0) text.append(buffer, std::size_t(n));
  int code = Z_OK;
  const std::string message = gzerror(in, &code);
  gzclose(in);
  // Z_BUF_ERROR: the input ended inside a gzip member (zlib's gzread documentation).
  if (n < 0 || (code != Z_OK && code != Z_BUF_ERROR))
    throw InputError(path.string(), "not readable as text or gzip: " + message);
  return {split_lines(text), code == Z_BUF_ERROR};
}

/// Writes `lines` to `path`, appended or anew, as gzip or plain text.
void put_lines(const std::filesystem::path& path, const std::vector<std::string>& lines, bool gzip,
               bool append) {
  std::string text;
  for (const auto& line : lines) text += line + "\n";
  if (gzip) {
    gzFile out = gzopen(path.c_str(), append ? "ab" : "wb");
    const bool ok = out && gzwrite(out, text.data(), unsigned(text.size())) == int(text.size());
    if (!out || gzclose(out) != Z_OK || !ok)
      throw std::runtime_error("cannot write " + path.string());
    return;
  }
  std::ofstream out(path, append ? std::ios::app : std::ios::trunc);
  out << text << std::flush;
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t start = 0;
  for (std::size_t end; (end = text.find('\n', start)) != std::string::npos; start = end + 1)
    lines.push_back(text.substr(start, end - start));
  if (start < text.size()) lines.push_back(text.substr(start));
  return lines;
}

std::string JsonLinesFile::where(std::size_t line) const {
  return path_.string() + ":" + std::to_string(line);
}

bool JsonLinesFile::gzip() const {
  return path_.extension() == ".gz";
}

void JsonLinesFile::read(const std::function<void(const std::string&, std::size_t)>& take,
                         const std::string& what) {
  if (!std::filesystem::exists(path_)) return;
  Contents c = read_lines(path_);
  bool rewrite = c.cut;
  if (c.cut) std::cerr << path_.string() << ": its gzip end was cut short while it was written\n";
  for (std::size_t i = 0; i < c.lines.size(); ++i) {
    try {
      take(c.lines[i], i + 1);
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      if (i + 1 < c.lines.size() || i == 0)
        throw InputError(where(i + 1), "not " + what + ": " + e.what());
      std::cerr << where(i + 1) << ": a line cut short while it was written, dropped\n";
      c.lines.pop_back();
      rewrite = true;
    }
  }
  if (rewrite) write(c.lines);
  lines_ = c.lines.size();
}

void JsonLinesFile::append(const std::vector<std::string>& lines) {
  put_lines(path_, lines, gzip(), true);
  lines_ += lines.size();
}

void JsonLinesFile::write(const std::vector<std::string>& lines) {
  const std::filesystem::path fresh = path_.string() + ".new";
  put_lines(fresh, lines, gzip(), false);
  std::filesystem::rename(fresh, path_);
  lines_ = lines.size();
}

}  // namespace demcal::cli
