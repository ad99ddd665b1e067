#pragma once
// Opening a page in Debian's headless Chromium from a test: --dump-dom gives the DOM after the
// page's scripts ran (Vega renders SVG, so every mark is an element a test can count) and its
// log carries every console message; no driver beyond the browser itself is needed.
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/common/command.hpp"

namespace demcal::test {

/// The page after its scripts ran, and every console message Chromium logged.
struct Page {
  std::string dom;
  std::vector<std::string> console;
};

/// The browser's command line up to the URL. Root in a container: no sandbox. Virtual time lets
/// the page's timers (the live page's poll) and Vega's asynchronous rendering finish before the
/// DOM is taken. A profile of its own under `dir`: no lock shared with a browser the user runs.
inline std::string chromium_flags(const std::filesystem::path& dir) {
  return "chromium --headless --no-sandbox --disable-gpu --hide-scrollbars "
         "--enable-logging=stderr --v=0 --virtual-time-budget=15000 --user-data-dir=" +
         (dir / "chromium-profile").string() + " ";
}

/// Opens `url`; the browser's log is kept as `dir`/`name`.chromium.log.
inline Page open_in_chromium(const std::string& url, const std::filesystem::path& dir,
                             const std::string& name) {
  const std::filesystem::path err = dir / (name + ".chromium.log");
  const CommandResult o =
      run_command(chromium_flags(dir) + "--dump-dom '" + url + "' 2>" + err.string());
  Page page{o.out, {}};
  std::ifstream log(err);
  for (std::string line; std::getline(log, line);)
    if (line.find(":CONSOLE") != std::string::npos) page.console.push_back(line);
  return page;
}

}  // namespace demcal::test
