// What the fuzz targets share: a reader that decodes values from the fuzzer's bytes (zeros once they run
// out, so every input decodes), the check that turns a broken promise of the library into a crash the
// fuzzer reports, and a scratch folder per process for the targets that must hand the library a file.
// Used by the libFuzzer builds (CAPE_FUZZ=ON) and by the regression runners of the ordinary build alike.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

namespace capefuzz {

/// A promise of the library's documentation that an input broke: say which and abort, so that libFuzzer
/// keeps the input (and the regression runner fails on it). Never for an error the library returned: bad
/// data coming back as a Status is the library working.
[[noreturn]] inline void broken(const char* where, const std::string& what) {
  std::fprintf(stderr, "cape fuzz: %s: %s\n", where, what.c_str());
  std::fflush(stderr);
  std::abort();
}

#define CAPE_FUZZ_CHECK(condition, what)                  \
  do {                                                    \
    if (!(condition)) ::capefuzz::broken(__func__, what); \
  } while (false)

/// Little-endian values read from the front of the input; once it is used up every value reads as zero.
class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::uint8_t u8() { return pos_ < size_ ? data_[pos_++] : 0; }
  std::uint16_t u16() {
    const std::uint16_t lo = u8();
    return static_cast<std::uint16_t>(lo | (u8() << 8));
  }
  std::uint32_t u32() {
    const std::uint32_t lo = u16();
    return lo | (static_cast<std::uint32_t>(u16()) << 16);
  }
  /// Any bit pattern, so NaN, infinities, denormals and 1e38 all come through.
  float rawFloat() {
    const std::uint32_t u = u32();
    float f = 0.0f;
    std::memcpy(&f, &u, sizeof f);
    return f;
  }
  /// A signed 16-bit count of `unit`s: finite, within +-32768 units.
  float fixed(float unit) { return static_cast<float>(static_cast<std::int16_t>(u16())) * unit; }
  std::size_t remaining() const { return size_ - pos_; }
  /// The bytes not read yet, as they are.
  std::string rest() {
    std::string s(reinterpret_cast<const char*>(data_ + pos_), size_ - pos_);
    pos_ = size_;
    return s;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

/// A folder of this process's own under the temporary directory, removed at a normal exit (a crashed run
/// leaves it behind: its name says whose it was).
class ScratchDir {
 public:
  static const std::filesystem::path& path() {
    static ScratchDir dir;
    return dir.path_;
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }

 private:
  ScratchDir() {
    std::error_code ec;
    std::filesystem::path base = std::filesystem::temp_directory_path(ec);
    if (ec) base = "/tmp";
    path_ = base / ("cape_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(path_, ec);
    if (ec) broken("ScratchDir", "cannot make " + path_.string() + ": " + ec.message());
  }
  std::filesystem::path path_;
};

/// Writes `bytes` to `path`, replacing what was there; a failure to write is the harness's problem, not
/// the library's, and stops the run.
inline void writeFile(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) broken("writeFile", "cannot write " + path.string());
}

/// The mesh formats a URDF <mesh> element is meant to name (character/README.md), picked by one byte.
inline const char* meshExtension(std::uint8_t selector) {
  static const char* const kExtensions[] = {"stl", "obj", "dae"};
  return kExtensions[selector % 3];
}

}  // namespace capefuzz
