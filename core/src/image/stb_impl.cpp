// The stb_image_write and stb_image implementations (PNG only), with libdeflate as the PNG
// compressor, behind the wrappers of stb_wrappers.h.
#include <libdeflate.h>

#include <climits>
#include <cstdint>
#include <cstdlib>
#include <memory>

#include "image/stb_wrappers.h"

namespace {

// stb's own deflate costs ~60 ms on an 800x600 image whatever its level; libdeflate at level 1
// is several times faster and, with the "up" filter, smaller too. stb asks for
// a zlib stream in memory from malloc, which it frees with free().
unsigned char* zlib_compress(unsigned char* data, int data_len, int* out_len, int /*quality*/) {
  using Compressor = std::unique_ptr<libdeflate_compressor, decltype(&libdeflate_free_compressor)>;
  Compressor compressor(libdeflate_alloc_compressor(1), &libdeflate_free_compressor);
  if (!compressor || data_len < 0) return nullptr;
  std::size_t bound = libdeflate_zlib_compress_bound(compressor.get(), data_len);
  auto* out = static_cast<unsigned char*>(std::malloc(bound));
  if (!out) return nullptr;
  std::size_t size = libdeflate_zlib_compress(compressor.get(), data, data_len, out, bound);
  if (size == 0 || size > INT_MAX) {
    std::free(out);
    return nullptr;
  }
  *out_len = static_cast<int>(size);
  return out;
}

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

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#define STBI_WRITE_NO_STDIO
#define STBIW_ZLIB_COMPRESS zlib_compress
#include <stb_image_write.h>

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

namespace {

void append(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<unsigned char>*>(context);
  auto* bytes = static_cast<const unsigned char*>(data);
  out->insert(out->end(), bytes, bytes + size);
}

}  // namespace

std::vector<unsigned char> encode_png(const unsigned char* pixels, int width, int height,
                                      int channels) {
  // stb reads this global on every encode: set it exactly once (a thread-safe static
  // initialisation), never per call, so concurrent encodes do not race on it.
  [[maybe_unused]] static const bool filter_forced = (stbi_write_force_png_filter = 2, true);
  std::vector<unsigned char> out;
  if (!stbi_write_png_to_func(append, &out, width, height, channels, pixels, 0)) out.clear();
  return out;
}

DecodedPng decode_png_rgb(const unsigned char* data, int size, std::size_t alloc_limit) {
  struct LimitScope {
    explicit LimitScope(std::size_t limit) { t_alloc_limit = limit; }
    ~LimitScope() { t_alloc_limit = SIZE_MAX; }
  } scope(alloc_limit);
  // Some failure paths return without setting a reason: clear this thread's previous one.
  stbi__g_failure_reason = nullptr;

  DecodedPng result;
  int channels = 0;
  std::unique_ptr<stbi_uc, FreeDeleter> pixels(
      stbi_load_from_memory(data, size, &result.width, &result.height, &channels, 3));
  if (!pixels) {
    const char* reason = stbi_failure_reason();
    result.error = reason ? reason : "corrupt data";
    return result;
  }
  auto* begin = pixels.get();
  result.rgb.assign(begin, begin + static_cast<std::size_t>(result.width) * result.height * 3);
  return result;
}

}  // namespace rayfarm::stb
