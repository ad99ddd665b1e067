#pragma once
// A file of JSON lines that a long computation appends to as its pieces finish (the runs of
// `demcal lab study --out`, a campaign's journal), so that the same command run again goes on
// from it. A process killed while it writes leaves its last line cut short: reading drops that
// line from the file. A file is read whether it is plain text or gzip; one whose name ends in
// .gz is written as gzip, each append a gzip member of its own (gzip reads the members as one
// text), so that a growing file is never rewritten.
#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace demcal::cli {

/// The lines of a text, without their newlines (a last line without one included).
std::vector<std::string> split_lines(const std::string& text);

class JsonLinesFile {
 public:
  explicit JsonLinesFile(std::filesystem::path path) : path_(std::move(path)) {}

  const std::filesystem::path& path() const { return path_; }
  /// "FILE:LINE", the place an error names.
  std::string where(std::size_t line) const;
  /// Lines in the file: those read and those appended since.
  std::size_t lines() const { return lines_; }

  /// Hands each line of the file (none when it does not exist) to `take` with its number
  /// (1-based). A line `take` throws on with anything but an InputError is a line cut short
  /// when it is the file's last and not its first: it is dropped from the file (and so is the
  /// damaged end of a gzip file cut short), with a note on standard error. Any other is an
  /// InputError naming the file and line: "not <what>: " and the reason.
  void read(const std::function<void(const std::string& text, std::size_t line)>& take,
            const std::string& what);
  /// Appends the lines (without their newlines); they have reached the operating system when
  /// it returns.
  void append(const std::vector<std::string>& lines);
  /// Writes the file anew with these lines, replacing it whole (written beside it, then renamed).
  void write(const std::vector<std::string>& lines);

 private:
  bool gzip() const;
  std::filesystem::path path_;
  std::size_t lines_ = 0;
};

}  // namespace demcal::cli
