// Tests for PNG/PPM encoding and decoding, including hostile and malformed input.
#include "rayfarm/image_io.h"

#include <gtest/gtest.h>
#include <libdeflate.h>

#include <cstdint>
#include <random>
#include <stdexcept>
#include <thread>

#include "rayfarm/sha256.h"
#include "test_util.h"

namespace rayfarm {
namespace {

Image random_image(int width, int height, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> byte(0, 255);
  Image image(width, height);
  for (auto& v : image.rgb) v = static_cast<std::uint8_t>(byte(rng));
  return image;
}

std::string_view view(const std::vector<unsigned char>& bytes) {
  return {reinterpret_cast<const char*>(bytes.data()), bytes.size()};
}

void put_be32(std::string& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out += static_cast<char>(v >> shift & 0xff);
}

std::string zlib(std::string_view data) {
  libdeflate_compressor* c = libdeflate_alloc_compressor(6);
  std::string out(libdeflate_zlib_compress_bound(c, data.size()), '\0');
  out.resize(libdeflate_zlib_compress(c, data.data(), data.size(), out.data(), out.size()));
  libdeflate_free_compressor(c);
  return out;
}

void put_chunk(std::string& png, std::string_view type, std::string_view data,
               std::uint32_t length) {
  put_be32(png, length);
  std::string body = std::string(type) + std::string(data);
  png += body;
  put_be32(png, libdeflate_crc32(0, body.data(), body.size()));
}

// A PNG built by hand, so that colour types the encoder never produces can be tested.
// `rows` are the raw scanlines, each with its leading filter byte.
// `palette`, when given, is written as a PLTE chunk before the data.
std::string make_png(std::uint32_t width, std::uint32_t height, int bit_depth, int colour_type,
                     std::string_view rows, std::string_view palette = {}, int interlace = 0) {
  std::string png("\x89PNG\r\n\x1a\n", 8);
  std::string ihdr;
  put_be32(ihdr, width);
  put_be32(ihdr, height);
  ihdr += {static_cast<char>(bit_depth), static_cast<char>(colour_type), 0, 0,
           static_cast<char>(interlace)};
  put_chunk(png, "IHDR", ihdr, 13);
  if (!palette.empty())
    put_chunk(png, "PLTE", palette, static_cast<std::uint32_t>(palette.size()));
  std::string idat = zlib(rows);
  put_chunk(png, "IDAT", idat, static_cast<std::uint32_t>(idat.size()));
  put_chunk(png, "IEND", "", 0);
  return png;
}

std::string decode_error(std::string_view bytes) {
  std::string error;
  auto image = decode_image(bytes, &error);
  EXPECT_FALSE(image) << "decoded unexpectedly: " << bytes.substr(0, 40);
  EXPECT_FALSE(error.empty());
  return error;
}

Image decode_ok(std::string_view bytes) {
  std::string error;
  auto image = decode_image(bytes, &error);
  EXPECT_TRUE(image) << error;
  return image.value_or(Image());
}

const std::pair<int, int> kSizes[] = {{1, 1}, {7, 3}, {1, 37}, {37, 1}, {64, 64}, {33, 17}};

TEST(ImageIo, PngRoundTripKeepsEveryPixel) {
  unsigned seed = 1;
  for (auto [w, h] : kSizes) {
    Image image = random_image(w, h, seed++);
    EXPECT_EQ(decode_ok(view(encode_png(image))), image) << w << "x" << h;
  }
}

// A PNG of a few KB can decode to tens of MB: the bound a server admits decodes by is read
// from its header, and covers what the decode really holds. A PPM holds its pixels.
TEST(ImageIo, DecodeMemoryBoundIsReadFromTheHeader) {
  Image big;
  big.width = 2048;
  big.height = 2048;
  big.rgb.assign(static_cast<std::size_t>(big.width) * big.height * 3, 0);
  const std::vector<unsigned char> png = encode_png(big);
  ASSERT_LT(png.size(), 100000u);
  EXPECT_GE(decode_memory_bound(view(png)), big.rgb.size() * 2);
  const std::vector<unsigned char> ppm = encode_ppm(big);
  EXPECT_GE(decode_memory_bound(view(ppm)), ppm.size());
  EXPECT_LT(decode_memory_bound(view(ppm)), 3 * ppm.size());
  EXPECT_EQ(decode_memory_bound("not an image"), 24u);
}

TEST(ImageIo, PpmRoundTripKeepsEveryPixel) {
  unsigned seed = 100;
  for (auto [w, h] : kSizes) {
    Image image = random_image(w, h, seed++);
    EXPECT_EQ(decode_ok(view(encode_ppm(image))), image) << w << "x" << h;
  }
}

TEST(ImageIo, PpmEncodingIsBinaryP6) {
  Image image(2, 1);
  image.rgb = {1, 2, 3, 4, 5, 6};
  auto ppm = encode_ppm(image);
  EXPECT_EQ(view(ppm), std::string_view("P6\n2 1\n255\n\x01\x02\x03\x04\x05\x06"));
}

TEST(ImageIo, EncodeImageFollowsTheFormat) {
  Image image = random_image(3, 2, 7);
  EXPECT_EQ(encode_image(image, ImageFormat::ppm), encode_ppm(image));
  EXPECT_EQ(encode_image(image, ImageFormat::png), encode_png(image));
}

TEST(ImageIo, PngRowsUseTheUpFilter) {
  Image image = random_image(5, 4, 3);
  auto png = encode_png(image);
  std::string_view bytes = view(png);
  ASSERT_TRUE(bytes.starts_with(std::string_view("\x89PNG\r\n\x1a\n", 8)));
  std::size_t idat = bytes.find("IDAT");
  ASSERT_NE(idat, std::string_view::npos);
  std::uint32_t length = 0;
  for (std::size_t i = idat - 4; i < idat; ++i) length = length << 8 | png[i];
  std::string raw(4 * (5 * 3 + 1), '\0');
  libdeflate_decompressor* d = libdeflate_alloc_decompressor();
  auto result =
      libdeflate_zlib_decompress(d, png.data() + idat + 4, length, raw.data(), raw.size(), nullptr);
  libdeflate_free_decompressor(d);
  ASSERT_EQ(result, LIBDEFLATE_SUCCESS);
  for (int row = 0; row < 4; ++row) EXPECT_EQ(raw[row * 16], 2) << "row " << row;
}

// The PNG writer must keep writing the bytes it wrote when stb_image_write (filter forced
// to "up", libdeflate level 1) encoded them: files and their hashes stay as they were. The
// images themselves are pinned by the golden test.
TEST(ImageIo, PngBytesAreTheEarlierEncodersBytes) {
  const Scene scene = test::scene_from(test::lecture_scene());
  RenderOptions small;
  small.width = 13;
  small.height = 7;
  const std::vector<unsigned char> tiny = encode_png(test::render(scene, small));
  EXPECT_EQ(sha256_hex(view(tiny)),
            "420bc00c7792ad57c74c2e3a87544aebcc69e11a996d5d34ade9308bfa272a0a");
  const std::vector<unsigned char> full = encode_png(test::render(scene, {}, 2));
  EXPECT_EQ(sha256_hex(view(full)),
            "346fbaa3120cce434c932d91944dab378efaad14740ead6bccd0d2ac6451b8c9");
}

TEST(ImageIo, ConcurrentPngEncodesAgree) {
  Image image = random_image(40, 30, 11);
  auto expected = encode_png(image);
  std::vector<std::vector<unsigned char>> results(8);
  std::vector<std::thread> threads;
  for (auto& result : results) {
    threads.emplace_back([&image, out = &result] { *out = encode_png(image); });
  }
  for (auto& t : threads) t.join();
  for (const auto& result : results) EXPECT_EQ(result, expected);
}

TEST(ImageIo, EncodersRefuseMalformedImages) {
  Image bad(2, 2);
  bad.rgb.pop_back();
  EXPECT_THROW(encode_png(bad), std::invalid_argument);
  EXPECT_THROW(encode_ppm(bad), std::invalid_argument);
  EXPECT_THROW(encode_png(Image()), std::invalid_argument);
  EXPECT_EQ(view(encode_ppm(Image())), "P6\n0 0\n255\n");
}

TEST(ImageIo, AsciiP3WithCommentsDecodes) {
  Image image = decode_ok("P3\n# made by hand\n2 # width\n1\n255\n255 0 0\t0 255 7\n");
  EXPECT_EQ(image.width, 2);
  EXPECT_EQ(image.height, 1);
  EXPECT_EQ(image.rgb, (std::vector<std::uint8_t>{255, 0, 0, 0, 255, 7}));
}

TEST(ImageIo, SmallMaxvalIsScaledTo255) {
  EXPECT_EQ(decode_ok("P3 1 1 15 15 0 7").rgb, (std::vector<std::uint8_t>{255, 0, 119}));
  EXPECT_EQ(decode_ok(std::string("P6 1 1 100\n\x64\x00\x32", 14)).rgb,
            (std::vector<std::uint8_t>{255, 0, 128}));
}

TEST(ImageIo, SixteenBitP6IsBigEndianAndScaledTo8Bits) {
  std::string ppm = "P6\n# 16 bit\n2 1\n65535\n";
  ppm += std::string("\xff\xff\x00\x00\x80\x80\x3c\x3c\x01\x01\x00\xff", 12);
  EXPECT_EQ(decode_ok(ppm).rgb, (std::vector<std::uint8_t>{255, 0, 128, 60, 1, 1}));
  EXPECT_EQ(decode_ok("P3 1 1 1000 1000 0 500").rgb, (std::vector<std::uint8_t>{255, 0, 128}));
}

// The same 16-bit samples in a PNG and in a PPM are the same picture: both are scaled to the
// nearest level (a high byte alone made 0xFF00 255 from the PNG and 254 from the PPM).
TEST(ImageIo, SixteenBitPngAndPpmScaleAlike) {
  std::string samples;
  for (int v : {0xff00, 0x0000, 0x8080, 0x7fff, 0x0080, 0x007f, 0xffff, 0x3c00, 0x0101})
    samples += {static_cast<char>(v >> 8), static_cast<char>(v & 0xff)};
  const std::vector<std::uint8_t> png = decode_ok(make_png(3, 1, 16, 2, '\0' + samples)).rgb;
  const std::vector<std::uint8_t> ppm = decode_ok("P6\n3 1\n65535\n" + samples).rgb;
  EXPECT_EQ(png, ppm);
  EXPECT_EQ(png, (std::vector<std::uint8_t>{254, 0, 128, 127, 0, 0, 255, 60, 1}));
}

TEST(ImageIo, TruncatedPpmDataReportsWhatWasMissing) {
  EXPECT_EQ(decode_error("P6\n2 2\n255\nabcde"), "truncated PPM data: expected 12 bytes, got 5");
  EXPECT_EQ(decode_error("P6\n2 2\n65535\nabcde"), "truncated PPM data: expected 24 bytes, got 5");
  EXPECT_EQ(decode_error("P3\n2 1\n255\n1 2 3 4"), "truncated PPM data: expected 6 samples, got 4");
  EXPECT_EQ(decode_error("P6\n2 2\n255"), "bad PPM header: no whitespace after maxval");
}

TEST(ImageIo, MalformedPpmHeadersAreErrors) {
  EXPECT_EQ(decode_error("P6"), "truncated PPM header: no width");
  EXPECT_EQ(decode_error("P6\n4 4\n"), "truncated PPM header: no maxval");
  EXPECT_EQ(decode_error("P6\nabc 2 255\n"), "bad PPM header: width 'abc' is not a whole number");
  EXPECT_EQ(decode_error("P6\n2 -2 255\n"), "bad PPM header: height '-2' is not a whole number");
  EXPECT_EQ(decode_error("P6\n2 2x 255\n"), "bad PPM header: height '2x' is not a whole number");
  EXPECT_EQ(decode_error("P612 2 255\n"), "bad PPM header: no whitespace after P6");
  EXPECT_EQ(decode_error("P6 1 1 0\n"), "bad PPM header: maxval 0 is not in 1..65535");
  EXPECT_EQ(decode_error("P6 1 1 65536\n"), "bad PPM header: maxval 65536 is not in 1..65535");
  EXPECT_EQ(decode_error("P3 1 1 255 1 2 x"), "bad PPM data: sample 3, 'x', is not a whole number");
  EXPECT_EQ(decode_error("P3 1 1 255 -1 2 3"), "bad PPM data: sample 1, '-1', is not a whole number");
  EXPECT_EQ(decode_error("P3 1 1 200 1 2 201"), "PPM sample 201 exceeds maxval 200");
  // As written, past the 2^32 the reader saturates at, and cut at 20 digits.
  EXPECT_EQ(decode_error("P3 1 1 5000000000 0 0 0"),
            "bad PPM header: maxval 5000000000 is not in 1..65535");
  EXPECT_EQ(decode_error("P3 1 1 255 0 0 4294967296"), "PPM sample 4294967296 exceeds maxval 255");
  EXPECT_EQ(decode_error("P3 1 1 255 0 0 " + std::string(30, '9')),
            "PPM sample " + std::string(20, '9') + "... exceeds maxval 255");
  EXPECT_EQ(decode_error("P6 1 1 9\n\x01\x02\x0a"), "PPM sample 10 exceeds maxval 9");
  EXPECT_EQ(decode_error("P5 1 1 255\n\x01"),
            "unsupported Netpbm type P5: only PPM (P3, P6) is read");
}

TEST(ImageIo, ZeroAndOversizedDimensionsAreRefusedBeforeAllocating) {
  EXPECT_EQ(decode_error("P6 0 5 255\n"), "image has no pixels (0x5)");
  EXPECT_EQ(decode_error("P3 5 0 255\n"), "image has no pixels (5x0)");
  EXPECT_EQ(decode_error("P6 100000 100000 255\n"),
            "image too large: 100000x100000 is over the limit of 67108864 pixels");
  EXPECT_EQ(decode_error("P6 99999999999999999999999 99999999999999999999999 255\n"),
            "bad PPM header: width '99999999999999999999...' is far too large");
  EXPECT_EQ(decode_error("P6 4294967297 1 255\n"),
            "bad PPM header: width '4294967297' is far too large");
  EXPECT_EQ(decode_error(make_png(65535, 65535, 8, 2, "")),
            "image too large: 65535x65535 is over the limit of 67108864 pixels");
  EXPECT_EQ(decode_error(make_png(0, 1, 8, 2, "")), "image has no pixels (0x1)");
}

TEST(ImageIo, GarbageIsNotAnImage) {
  EXPECT_EQ(decode_error(""), "not a PNG or PPM image");
  EXPECT_EQ(decode_error("P"), "not a PNG or PPM image");
  EXPECT_EQ(decode_error("hello world"), "not a PNG or PPM image");
  EXPECT_EQ(decode_error(std::string_view("\x89PNG\r\n\x1a", 7)), "not a PNG or PPM image");
  EXPECT_EQ(decode_error(std::string_view("\x89PNG\r\n\x1b\n rest", 13)), "not a PNG or PPM image");
  EXPECT_EQ(decode_error(std::string_view("\x89PNG\r\n\x1a\n", 8)),
            "corrupt PNG: no IHDR chunk after the signature");
}

TEST(ImageIo, TruncatedPngNeverCrashes) {
  Image image = random_image(9, 7, 5);
  auto png = encode_png(image);
  for (std::size_t n = 0; n < png.size(); ++n) {
    std::string error;
    auto decoded = decode_image(view(png).substr(0, n), &error);
    // Only the trailing IEND CRC may go missing unnoticed.
    if (decoded) {
      EXPECT_EQ(*decoded, image);
    } else {
      EXPECT_FALSE(error.empty());
    }
  }
}

TEST(ImageIo, RandomBytesAfterValidSignaturesNeverCrash) {
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> byte(0, 255);
  const std::string prefixes[] = {std::string("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR", 16), "P6 ", "P3 ",
                                  "P6 3 2 ", "P6 2 2 65535\n"};
  for (int i = 0; i < 2000; ++i) {
    std::string bytes = prefixes[i % 5];
    int extra = byte(rng);
    for (int k = 0; k < extra; ++k) bytes += static_cast<char>(byte(rng) % (i % 2 ? 256 : 64));
    std::string error;
    decode_image(bytes, &error);
  }
}

TEST(ImageIo, PngWithAlphaGreyOrSixteenBitsDecodesToRgb) {
  std::string rgba("\0\x0a\x14\x1e\xff\x28\x32\x3c\x00", 9);
  EXPECT_EQ(decode_ok(make_png(2, 1, 8, 6, rgba)).rgb,
            (std::vector<std::uint8_t>{10, 20, 30, 40, 50, 60}));
  std::string grey("\0\x07\xf0", 3);
  EXPECT_EQ(decode_ok(make_png(2, 1, 8, 0, grey)).rgb,
            (std::vector<std::uint8_t>{7, 7, 7, 240, 240, 240}));
  std::string rgb16("\0\xff\xff\x00\x00\x80\x80", 7);
  EXPECT_EQ(decode_ok(make_png(1, 1, 16, 2, rgb16)).rgb, (std::vector<std::uint8_t>{255, 0, 128}));
}

// Found by fuzzing: stb_image copied from a null pointer (UBSan) for a leading empty IDAT.
TEST(ImageIo, EmptyIdatChunksAreSkipped) {
  std::string rows("\0\x01\x02\x03", 4);
  std::string png = make_png(1, 1, 8, 2, rows);
  std::string with_empty = png.substr(0, 33);  // signature and IHDR
  put_chunk(with_empty, "IDAT", "", 0);
  with_empty += png.substr(33, png.size() - 33 - 12);
  put_chunk(with_empty, "IDAT", "", 0);
  put_chunk(with_empty, "IEND", "", 0);
  EXPECT_EQ(decode_ok(with_empty).rgb, (std::vector<std::uint8_t>{1, 2, 3}));
  decode_error(with_empty.substr(0, 33 + 8));  // the empty IDAT cut before its CRC
}

// A PNG cut anywhere after its header says it was cut short, in words (stb_image's own
// reasons are codes such as "outofdata", or a chunk type's first letters).
TEST(ImageIo, ACutPngSaysSo) {
  const std::vector<unsigned char> png = encode_png(random_image(9, 7, 5));
  std::size_t refused = 0;
  for (std::size_t n = 33; n + 12 < png.size(); ++n) {
    std::string why;
    if (decode_image(view(png).substr(0, n), &why)) continue;
    ++refused;
    EXPECT_EQ(why, "cannot decode PNG: the file is cut short (it does not end with the IEND "
                   "chunk)")
        << n;
  }
  EXPECT_GT(refused, 20u);
}

TEST(ImageIo, PngDataInflatingFarBeyondItsHeaderIsRefused) {
  std::string rows(16 << 20, '\0');  // 16 MiB of scanlines for a 1x1 image
  EXPECT_EQ(decode_error(make_png(1, 1, 8, 2, rows)),
            "cannot decode PNG: data larger than its size");
}

TEST(ImageIo, PngChunkClaimingGigabytesIsRefused) {
  std::string png = make_png(1, 1, 8, 2, std::string(4, '\0'));
  std::string hostile = png.substr(0, 33);  // signature and IHDR
  put_chunk(hostile, "IDAT", "short", 0x7ffffff0);
  EXPECT_EQ(decode_error(hostile),
            "cannot decode PNG: data larger than its size");  // not even tried
}


// Damage the format can detect is refused, as libpng refuses it, with where it is: stb_image
// alone decoded these to whatever pixels the damage left.
TEST(ImageIo, ACriticalChunkFailingItsCrcIsRefused) {
  const std::vector<unsigned char> good = encode_png(random_image(9, 7, 5));
  std::string png(view(good));
  png[33 + 8 + 5] ^= 0x10;  // a byte of the image data (IDAT follows the signature and IHDR)
  EXPECT_EQ(decode_error(png),
            "corrupt PNG: chunk IDAT at byte 33 fails its CRC check (the file is damaged)");
  png = std::string(view(good));
  png[16 + 3] ^= 1;  // the width
  EXPECT_EQ(decode_error(png),
            "corrupt PNG: chunk IHDR at byte 8 fails its CRC check (the file is damaged)");
}

TEST(ImageIo, AnAncillaryChunkFailingItsCrcIsSkipped) {
  const Image image = random_image(9, 7, 5);
  const std::vector<unsigned char> good = encode_png(image);
  std::string png(view(good).substr(0, 33));
  put_be32(png, 5);
  png += std::string("tEXtab\0cd", 9);
  put_be32(png, 12345);  // not the CRC
  png += view(good).substr(33);
  EXPECT_EQ(decode_ok(png), image);
}

TEST(ImageIo, TheImageDatasAdler32IsChecked) {
  const std::string rows("\0\x01\x02\x03\0\x04\x05\x06", 8);
  std::string data = zlib(rows);
  data.back() ^= 1;  // the stream's Adler-32 ends it
  std::string png = make_png(1, 2, 8, 2, rows);
  std::string damaged = png.substr(0, 33);
  put_chunk(damaged, "IDAT", data, static_cast<std::uint32_t>(data.size()));
  put_chunk(damaged, "IEND", "", 0);
  EXPECT_EQ(decode_error(damaged), "corrupt PNG: the image data does not inflate (its zlib "
                                   "stream is damaged or fails its Adler-32 check)");
  EXPECT_EQ(decode_ok(png).rgb, (std::vector<std::uint8_t>{1, 2, 3, 4, 5, 6}));
}

TEST(ImageIo, HeaderFieldsTheFormatDoesNotHaveAreNamed) {
  const std::string rows("\0\x01\x02\x03", 4);
  EXPECT_EQ(decode_error(make_png(1, 1, 4, 2, rows)),
            "corrupt PNG: bit depth 4 is not allowed with colour type 2 (RGB): 8 or 16");
  EXPECT_EQ(decode_error(make_png(1, 1, 16, 3, rows)),
            "corrupt PNG: bit depth 16 is not allowed with colour type 3 (palette): 1, 2, 4 or 8");
  EXPECT_EQ(decode_error(make_png(1, 1, 8, 5, rows)),
            "corrupt PNG: colour type 5 does not exist (0, 2, 3, 4 or 6)");
  EXPECT_EQ(decode_error(make_png(1, 1, 8, 2, rows, {}, 2)),
            "corrupt PNG: interlace method 2 does not exist (0 or 1)");
  EXPECT_EQ(decode_error(make_png(1, 1, 8, 2, std::string("\x05\x01\x02\x03", 4))),
            "corrupt PNG: row 0 has filter type 5, which does not exist (0-4)");
  EXPECT_EQ(decode_error(make_png(2, 2, 8, 2, std::string(7, '\0'))),
            "corrupt PNG: the image data holds 7 bytes of the 14 its size needs");
  EXPECT_EQ(decode_error(make_png(1, 1, 8, 3, std::string(2, '\0'))),
            "corrupt PNG: a palette image (colour type 3) has no PLTE chunk");
}

unsigned char paeth_of(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return static_cast<unsigned char>(pa <= pb && pa <= pc ? a : pb <= pc ? b : c);
}

// The scanlines of a palette image, packed at `depth` bits, each row filtered with the next
// of the five filter types in turn; Adam7's passes when `interlaced`.
std::string palette_rows(int width, int height, int depth, const std::vector<int>& index,
                         bool interlaced) {
  struct Pass {
    int x0, y0, dx, dy;
  };
  const std::vector<Pass> passes =
      interlaced ? std::vector<Pass>{{0, 0, 8, 8}, {4, 0, 8, 8}, {0, 4, 4, 8}, {2, 0, 4, 4},
                                     {0, 2, 2, 4}, {1, 0, 2, 2}, {0, 1, 1, 2}}
                 : std::vector<Pass>{{0, 0, 1, 1}};
  std::string out;
  int filter = 0;
  for (const Pass& p : passes) {
    const int w = width > p.x0 ? (width - p.x0 + p.dx - 1) / p.dx : 0;
    const int h = height > p.y0 ? (height - p.y0 + p.dy - 1) / p.dy : 0;
    if (w == 0 || h == 0) continue;
    std::string prev;
    for (int j = 0; j < h; ++j) {
      std::string row((w * depth + 7) / 8, '\0');
      for (int i = 0; i < w; ++i) {
        const int bit = i * depth, v = index[(p.y0 + j * p.dy) * width + p.x0 + i * p.dx];
        row[bit / 8] = static_cast<char>(row[bit / 8] | v << (8 - depth - bit % 8));
      }
      out += static_cast<char>(filter);
      for (std::size_t k = 0; k < row.size(); ++k) {
        const int x = static_cast<unsigned char>(row[k]);
        const int a = k ? static_cast<unsigned char>(row[k - 1]) : 0;
        const int b = prev.empty() ? 0 : static_cast<unsigned char>(prev[k]);
        const int c = k && !prev.empty() ? static_cast<unsigned char>(prev[k - 1]) : 0;
        const int predicted = filter == 1 ? a : filter == 2 ? b : filter == 3 ? (a + b) / 2
                              : filter == 4 ? paeth_of(a, b, c) : 0;
        out += static_cast<char>(x - predicted);
      }
      prev = row;
      filter = (filter + 1) % 5;
    }
  }
  return out;
}

// Image data running past what the image needs is accepted, as decoders accept it, but its
// Adler-32 and palette indices are checked all the same.
TEST(ImageIo, DataPastTheImageIsStillChecked) {
  const std::string palette("\x10\x20\x30", 3);
  const std::string rows("\0\x00\x00\0\0", 5);  // 2x1 at depth 8, then two bytes more
  EXPECT_EQ(decode_ok(make_png(2, 1, 8, 3, rows, palette)).rgb,
            (std::vector<std::uint8_t>{0x10, 0x20, 0x30, 0x10, 0x20, 0x30}));
  const std::string past("\0\x00\xc8\0\0", 5);
  EXPECT_EQ(decode_error(make_png(2, 1, 8, 3, past, palette)),
            "corrupt PNG: palette index 200 at pixel (1, 0) is past the palette's 1 colours");
  std::string data = zlib(rows);
  data.back() ^= 1;
  std::string png = make_png(2, 1, 8, 3, rows, palette);
  std::string damaged = png.substr(0, png.find("IDAT") - 4);
  put_chunk(damaged, "IDAT", data, static_cast<std::uint32_t>(data.size()));
  put_chunk(damaged, "IEND", "", 0);
  EXPECT_EQ(decode_error(damaged), "corrupt PNG: the image data does not inflate (its zlib "
                                   "stream is damaged or fails its Adler-32 check)");
}

// IEND's CRC guards no pixel: a damaged one is no reason to refuse the image. An empty PLTE
// is said as such.
TEST(ImageIo, IendsCrcAndAnEmptyPaletteAreSaidAsWhatTheyAre) {
  const Image image = random_image(5, 4, 9);
  const std::vector<unsigned char> good = encode_png(image);
  std::string png(view(good));
  png[png.size() - 1] ^= 0x55;
  EXPECT_EQ(decode_ok(png), image);
  std::string empty("\x89PNG\r\n\x1a\n", 8);
  std::string ihdr;
  put_be32(ihdr, 1);
  put_be32(ihdr, 1);
  ihdr += {8, 3, 0, 0, 0};
  put_chunk(empty, "IHDR", ihdr, 13);
  put_chunk(empty, "PLTE", "", 0);
  const std::string idat = zlib(std::string(2, '\0'));
  put_chunk(empty, "IDAT", idat, static_cast<std::uint32_t>(idat.size()));
  put_chunk(empty, "IEND", "", 0);
  EXPECT_EQ(decode_error(empty), "corrupt PNG: the PLTE chunk holds no colours");
}

// Every index is checked against the palette, through every filter type, at every bit depth,
// interlaced or not; an index past it is named with its pixel.
TEST(ImageIo, PaletteIndicesPastThePaletteAreRefusedWithTheirPixel) {
  std::mt19937 rng(7);
  for (int depth : {1, 2, 4, 8}) {
    for (bool interlaced : {false, true}) {
      SCOPED_TRACE("depth " + std::to_string(depth) + (interlaced ? ", interlaced" : ""));
      // A full palette first: every index is fine, and the pixels are stb's.
      const int width = 13, height = 11;
      std::string palette;
      for (int i = 0; i < (1 << depth) * 3; ++i) palette += static_cast<char>(rng() & 0xff);
      std::vector<int> index(width * height);
      for (int& v : index) v = static_cast<int>(rng() % (1 << depth));
      const Image image =
          decode_ok(make_png(width, height, depth, 3,
                             palette_rows(width, height, depth, index, interlaced), palette,
                             interlaced));
      ASSERT_EQ(image.rgb.size(), index.size() * 3);
      for (std::size_t i = 0; i < index.size(); ++i)
        for (int k = 0; k < 3; ++k)
          ASSERT_EQ(image.rgb[i * 3 + k], static_cast<unsigned char>(palette[index[i] * 3 + k]));
      // Then one colour short, and one pixel naming the missing colour.
      const int colours = (1 << depth) - 1;
      palette.resize(colours * 3);
      for (int& v : index) v = static_cast<int>(rng() % colours);
      index[5 * width + 7] = colours;
      EXPECT_EQ(decode_error(make_png(width, height, depth, 3,
                                      palette_rows(width, height, depth, index, interlaced),
                                      palette, interlaced)),
                "corrupt PNG: palette index " + std::to_string(colours) +
                    " at pixel (7, 5) is past the palette's " + std::to_string(colours) +
                    " colours");
    }
  }
}

}  // namespace
}  // namespace rayfarm
