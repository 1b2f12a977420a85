// The stb_image implementation (PNG only), behind the wrapper of stb_wrappers.h.
#include <cstdint>
#include <cstdlib>
#include <memory>

#include "image/stb_wrappers.h"

namespace {

struct FreeDeleter {
  void operator()(void* p) const { std::free(p); }
};

thread_local std::size_t t_alloc_limit = SIZE_MAX;

void* capped_malloc(std::size_t size) {
  return size <= t_alloc_limit ? std::malloc(size) : nullptr;
}
void* capped_realloc(void* p, std::size_t size) {
  return size <= t_alloc_limit ? std::realloc(p, size) : nullptr;
}

}  // namespace

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"

#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#define STBI_ONLY_PNG
#define STBI_NO_STDIO
#define STBI_NO_LINEAR
#define STBI_MAX_DIMENSIONS (1 << 26)  // a 1-pixel-wide image may use all of kMaxDecodePixels
#define STBI_MALLOC(size) capped_malloc(size)
#define STBI_REALLOC(p, size) capped_realloc(p, size)
#define STBI_FREE(p) std::free(p)
#include <stb_image.h>

#pragma GCC diagnostic pop

namespace rayfarm::stb {

DecodedPng decode_png_rgb(const unsigned char* data, int size, std::size_t alloc_limit) {
  struct LimitScope {
    explicit LimitScope(std::size_t limit) { t_alloc_limit = limit; }
    ~LimitScope() { t_alloc_limit = SIZE_MAX; }
  } scope(alloc_limit);
  // Some failure paths return without setting a reason: clear this thread's previous one.
  stbi__g_failure_reason = nullptr;

  DecodedPng result;
  int channels = 0;
  auto failed = [&result] {
    const char* reason = stbi_failure_reason();
    result.error = reason ? reason : "corrupt data";
    return result;
  };
  // 16-bit samples are scaled to 8 bits to the nearest level, as a PPM's are (stb itself keeps
  // the high byte): one picture graded in either format gets the same bytes.
  if (stbi_is_16_bit_from_memory(data, size)) {
    std::unique_ptr<stbi_us, FreeDeleter> wide(
        stbi_load_16_from_memory(data, size, &result.width, &result.height, &channels, 3));
    if (!wide) return failed();
    const std::size_t n = static_cast<std::size_t>(result.width) * result.height * 3;
    result.rgb.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      result.rgb[i] = static_cast<std::uint8_t>((wide.get()[i] * 255u + 32767u) / 65535u);
    return result;
  }
  std::unique_ptr<stbi_uc, FreeDeleter> pixels(
      stbi_load_from_memory(data, size, &result.width, &result.height, &channels, 3));
  if (!pixels) return failed();
  auto* begin = pixels.get();
  result.rgb.assign(begin, begin + static_cast<std::size_t>(result.width) * result.height * 3);
  return result;
}

}  // namespace rayfarm::stb
