// Running a demo binary from a test: its exit status and everything it printed, in a fresh folder.
#pragma once

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <vector>

namespace cape::demo_test {

struct Result {
  int exitCode = -1;
  std::string output;  ///< stdout and stderr together
};

/// Runs `command` through the shell with stderr folded into stdout.
inline Result run(const std::string& command) {
  Result r;
  std::FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return r;
  char buffer[4096];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, p)) > 0) r.output.append(buffer, n);
  const int status = pclose(p);
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

/// This process's folder under the temporary directory, named after the process (two test runs at once on
/// one machine must not share it), which holds one fresh folder per test. Removed when the process ends,
/// unless a test failed: then what the demos wrote is kept, and the path is printed.
class ProcessFolder {
 public:
  static const std::filesystem::path& path() {
    // Made on the first use in a test, after GoogleTest's own UnitTest: destroyed before it.
    static ProcessFolder folder;
    return folder.path_;
  }
  ProcessFolder(const ProcessFolder&) = delete;
  ProcessFolder& operator=(const ProcessFolder&) = delete;

 private:
  ProcessFolder()
      : path_(std::filesystem::temp_directory_path() / ("cape_demo_tests-" + std::to_string(::getpid()))) {}
  ~ProcessFolder() {
    if (::testing::UnitTest::GetInstance()->Failed()) {
      std::fprintf(stderr, "the demos' outputs are kept in %s\n", path_.c_str());
      return;
    }
    std::error_code ignored;  // nothing to report at exit: a folder left behind is only untidy
    std::filesystem::remove_all(path_, ignored);
  }
  std::filesystem::path path_;
};

/// A fresh, empty folder in this process's folder (ProcessFolder), named after the running test.
inline std::filesystem::path freshDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::filesystem::path dir =
      ProcessFolder::path() / (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::vector<std::string> lines(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::vector<std::string> out;
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) out.push_back(line);
  return out;
}

/// Counts lines of an OBJ file starting with `prefix` ("v ", "vn ", "vt ", "f ").
inline int countPrefixed(const std::filesystem::path& file, const std::string& prefix) {
  int count = 0;
  for (const std::string& l : lines(file)) count += l.rfind(prefix, 0) == 0 ? 1 : 0;
  return count;
}

}  // namespace cape::demo_test
