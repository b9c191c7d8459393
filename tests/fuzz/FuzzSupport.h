// What the fuzz targets share: a reader that decodes values from the fuzzer's bytes (zeros once they run
// out, so every input decodes), the check that turns a broken promise of the library into a crash the
// fuzzer reports, and a scratch folder per process for the targets that must hand the library a file.
// Used by the libFuzzer builds (CAPE_FUZZ=ON) and by the regression runners of the ordinary build alike.
#pragma once

#include <sys/mman.h>
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

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CAPE_FUZZ_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) && !defined(CAPE_FUZZ_ASAN)
#define CAPE_FUZZ_ASAN 1
#endif
#if defined(CAPE_FUZZ_ASAN)
// sanitizer/allocator_interface.h (clang's; GCC ships the runtime's function but not the header).
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*malloc_hook)(const volatile void*,
                                                                             std::size_t),
                                                         void (*free_hook)(const volatile void*));
#endif

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

/// Under AddressSanitizer: every block of 4 MiB or more is backed by transparent huge pages where the
/// kernel has them (madvise, set up once per process). ASan maps each such block afresh (no reuse, as
/// glibc's heap would after the first) and assimp's OBJ reader fills a 16 MiB line buffer on every load:
/// 4,096 page faults per input, which made page faults most of mesh_hull's time on OBJ inputs (300 ms each
/// on the shared development machine). With 2 MiB pages the same bytes are written in a few faults. Only
/// the pages change: every allocation, check and report of ASan stays as it was. Nothing without ASan.
/// Each such block and its shadow are then faulted in by one madvise(MADV_POPULATE_WRITE) each, where the
/// kernel has it (a virtual machine pays for every page-fault exception).
inline void hugePagesForLargeBlocks() {
#if defined(CAPE_FUZZ_ASAN)
  static const bool installed = [] {
    __sanitizer_install_malloc_and_free_hooks(
        [](const volatile void* block, std::size_t size) {
          constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
          if (size < (std::size_t{4} << 20)) return;
          const std::uintptr_t start = reinterpret_cast<std::uintptr_t>(block);
          const std::uintptr_t begin = (start + kHuge - 1) & ~(kHuge - 1),
                               end = (start + size) & ~(kHuge - 1);
          if (end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
          // Then every page of the block, and of its shadow (ASan's: one byte per 8, at addr / 8 +
          // 0x7fff8000 on x86-64 Linux), faulted in by one call each instead of one exception a page.
          // MADV_POPULATE_WRITE (Linux 5.14) leaves the bytes as they are (zero, as mapped); an older
          // kernel refuses it and nothing changes.
          constexpr int kPopulateWrite = 23;  // MADV_POPULATE_WRITE, not in every libc's headers
          constexpr std::uintptr_t kPage = 4096, kShadowOffset = 0x7fff8000;
          const std::uintptr_t first = start & ~(kPage - 1), last = (start + size + kPage - 1) & ~(kPage - 1);
          ::madvise(reinterpret_cast<void*>(first), last - first, kPopulateWrite);
          const std::uintptr_t shadowFirst = ((first >> 3) + kShadowOffset) & ~(kPage - 1),
                               shadowLast = (((last >> 3) + kShadowOffset) + kPage - 1) & ~(kPage - 1);
          ::madvise(reinterpret_cast<void*>(shadowFirst), shadowLast - shadowFirst, kPopulateWrite);
        },
        [](const volatile void*) {});
    return true;
  }();
  (void)installed;
#endif
}

/// The mesh formats a URDF <mesh> element is meant to name (character/README.md), picked by one byte.
inline const char* meshExtension(std::uint8_t selector) {
  static const char* const kExtensions[] = {"stl", "obj", "dae"};
  return kExtensions[selector % 3];
}

}  // namespace capefuzz
