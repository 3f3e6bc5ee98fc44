#pragma once
// Config texts for tests: a minimal config with some lines changed.
#include <sstream>
#include <string>
#include <vector>

namespace rgbdtam::testing {

// `base` followed by `changes`, where a key set in `changes` replaces its line in `base` (a
// file that gives a key twice is an error of its own).
inline std::string with_changes(const std::string& base, const std::string& changes) {
  auto key_of = [](const std::string& line) {
    const size_t eq = line.find('=');
    if (eq == std::string::npos || line.find('#') < eq) return std::string();
    const size_t first = line.find_first_not_of(' ');
    const size_t last = line.find_last_not_of(' ', eq - 1);
    return first < eq ? line.substr(first, last - first + 1) : std::string();
  };
  std::vector<std::string> changed_keys;
  std::istringstream in(changes);
  for (std::string line; std::getline(in, line);) changed_keys.push_back(key_of(line));
  std::string out;
  std::istringstream lines(base);
  for (std::string line; std::getline(lines, line);) {
    const std::string key = key_of(line);
    bool replaced = false;
    for (const std::string& k : changed_keys) replaced = replaced || (!key.empty() && k == key);
    if (!replaced) out += line + "\n";
  }
  return out + changes;
}

}  // namespace rgbdtam::testing
