// The regression runner: one fuzz target's LLVMFuzzerTestOneInput, compiled without libFuzzer, fed every
// file under the folders given (its regression corpus, the generated large inputs, the seeds), each as one
// fuzzer input. A crash or a failed check aborts (ctest reports the file named last); an input that takes
// longer than the limit fails the run. Usage: cape_fuzz_regress_<target> [--limit SECONDS] DIR|FILE...
#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

namespace fs = std::filesystem;

// Files under `p` (itself when a file), sorted, dot files left out (.gitkeep).
bool collect(const fs::path& p, std::vector<fs::path>& out) {
  std::error_code ec;
  if (fs::is_regular_file(p, ec)) {
    out.push_back(p);
    return true;
  }
  if (!fs::is_directory(p, ec)) return false;
  std::vector<fs::path> found;
  for (fs::recursive_directory_iterator it(p, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file() && it->path().filename().string().front() != '.') found.push_back(it->path());
  if (ec) return false;
  std::sort(found.begin(), found.end());
  out.insert(out.end(), found.begin(), found.end());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  // Issue 14: a hang is an input over 2 s. Unoptimised or sanitized builds run the same code several times
  // slower, so they get ten times as long.
#if defined(NDEBUG) && !defined(__SANITIZE_ADDRESS__)
  double limit = 2.0;
#else
  double limit = 20.0;
#endif
  std::vector<fs::path> files;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--limit" && a + 1 < argc) {
      limit = std::atof(argv[++a]);
      continue;
    }
    if (!collect(arg, files)) {
      std::fprintf(stderr, "no such file or folder: %s\n", arg.c_str());
      return 2;
    }
  }
  if (files.empty()) {
    std::fprintf(stderr, "usage: %s [--limit SECONDS] DIR|FILE... (no input files found)\n", argv[0]);
    return 2;
  }
  int slow = 0;
  for (const fs::path& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::printf("%s (%zu bytes) ... ", f.string().c_str(), bytes.size());
    std::fflush(stdout);
    const auto start = std::chrono::steady_clock::now();
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const bool tooSlow = seconds > limit;
    slow += tooSlow ? 1 : 0;
    std::printf("%.3f s%s\n", seconds, tooSlow ? "  TOO SLOW" : "");
  }
  std::printf("%zu inputs, %d over %.1f s\n", files.size(), slow, limit);
  return slow == 0 ? 0 : 1;
}
