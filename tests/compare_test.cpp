// Tests for image comparison metrics and the difference heat map.
#include "rayfarm/compare.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace rayfarm {
namespace {

Image filled(int width, int height, std::uint8_t value) {
  Image image(width, height);
  std::fill(image.rgb.begin(), image.rgb.end(), value);
  return image;
}

void set_pixel(Image& image, int x, int y, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  std::uint8_t* p = image.row(y) + x * 3;
  p[0] = r;
  p[1] = g;
  p[2] = b;
}

// Black left of column `edge`, white from it on.
Image edge_image(int width, int height, int edge) {
  Image image(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = edge; x < width; ++x) set_pixel(image, x, y, 255, 255, 255);
  }
  return image;
}

CompareResult compare(const Image& a, const Image& b, CompareOptions options = {}) {
  std::string error;
  auto result = compare_images(a, b, options, &error);
  EXPECT_TRUE(result) << error;
  return result.value_or(CompareResult{});
}

int brightest_channel(const Image& image, int x, int y) {
  const std::uint8_t* p = image.row(y) + x * 3;
  return std::max({p[0], p[1], p[2]});
}

TEST(CompareImages, IdenticalImagesHaveNoErrorAndInfinitePsnr) {
  Image a = edge_image(5, 4, 2);
  CompareResult r = compare(a, a);
  EXPECT_EQ(r.width, 5);
  EXPECT_EQ(r.height, 4);
  EXPECT_EQ(r.rmse, 0);
  EXPECT_EQ(r.psnr, std::numeric_limits<double>::infinity());
  EXPECT_EQ(r.max_abs, 0);
  EXPECT_EQ(r.mean_abs, 0);
  EXPECT_EQ(r.differing_pixels, 0);
  EXPECT_EQ(r.differing_fraction, 0);
  EXPECT_EQ(r.off_by_more_than_1, 0);
}

TEST(CompareImages, EmptyImagesCompareAsIdentical) {
  CompareResult r = compare(Image(), Image());
  EXPECT_EQ(r.rmse, 0);
  EXPECT_EQ(r.differing_fraction, 0);
}

TEST(CompareImages, SinglePixelDifferenceGivesHandComputedMetrics) {
  Image a = filled(2, 2, 100);
  Image b = a;
  set_pixel(b, 1, 0, 110, 97, 100);  // channel differences 10 and 3 over 12 samples
  CompareResult r = compare(a, b);
  EXPECT_DOUBLE_EQ(r.rmse, std::sqrt(109.0 / 12));
  EXPECT_DOUBLE_EQ(r.psnr, 20 * std::log10(255 / std::sqrt(109.0 / 12)));
  EXPECT_DOUBLE_EQ(r.mean_abs, 13.0 / 12);
  EXPECT_EQ(r.max_abs, 10);
  EXPECT_EQ(r.differing_pixels, 1);
  EXPECT_DOUBLE_EQ(r.differing_fraction, 0.25);
  EXPECT_EQ(r.off_by_more_than_1, 1);
}

TEST(CompareImages, ThresholdForgivesDifferencesUpToItsValue) {
  Image a = filled(3, 3, 50);
  Image b = a;
  set_pixel(b, 0, 0, 55, 50, 50);
  set_pixel(b, 2, 2, 50, 50, 44);
  EXPECT_EQ(compare(a, b, {.threshold = 6}).differing_pixels, 0);
  EXPECT_EQ(compare(a, b, {.threshold = 5}).differing_pixels, 1);
  EXPECT_EQ(compare(a, b, {.threshold = 4}).differing_pixels, 2);
  EXPECT_EQ(compare(a, b, {.threshold = 4}).max_abs, 6);
}

TEST(CompareImages, OffByOneIsNotOffByMoreThanOne) {
  Image a = filled(4, 1, 200);
  Image b = a;
  set_pixel(b, 0, 0, 201, 199, 200);
  set_pixel(b, 3, 0, 198, 200, 200);
  CompareResult r = compare(a, b);
  EXPECT_EQ(r.off_by_more_than_1, 1);
  EXPECT_EQ(r.differing_pixels, 2);
}

TEST(CompareImages, NeighborhoodForgivesAnEdgeShiftedByOnePixel) {
  Image a = edge_image(8, 6, 4);
  Image b = edge_image(8, 6, 5);
  EXPECT_EQ(compare(a, b).differing_pixels, 6);
  EXPECT_EQ(compare(a, b, {.neighborhood = true}).differing_pixels, 0);
  EXPECT_EQ(compare(a, edge_image(8, 6, 6), {.neighborhood = true}).differing_pixels, 12);
}

TEST(CompareImages, NeighborhoodStillCountsADotMissingFromEitherImage) {
  Image plain = filled(7, 7, 0);
  Image dotted = plain;
  set_pixel(dotted, 3, 3, 255, 255, 255);
  EXPECT_EQ(compare(plain, dotted, {.neighborhood = true}).differing_pixels, 1);
  EXPECT_EQ(compare(dotted, plain, {.neighborhood = true}).differing_pixels, 1);
  Image corner = plain;
  set_pixel(corner, 6, 6, 255, 0, 0);
  EXPECT_EQ(compare(plain, corner, {.neighborhood = true}).differing_pixels, 1);
}

TEST(CompareImages, DifferentSizesAreAnError) {
  std::string error;
  EXPECT_FALSE(compare_images(Image(800, 600), Image(400, 300), {}, &error));
  EXPECT_EQ(error, "image sizes differ: 800x600 vs 400x300");
  EXPECT_FALSE(compare_images(Image(2, 3), Image(3, 2), {}, nullptr));
}

TEST(DiffImage, IsBlackWhereEqualAndBrightWhereDifferent) {
  Image a = filled(4, 3, 80);
  Image b = a;
  set_pixel(b, 1, 1, 81, 80, 80);   // differs by 1, over threshold 0
  set_pixel(b, 3, 2, 80, 255, 80);  // differs by 175
  Image diff = diff_image(a, b, {});
  ASSERT_EQ(diff.width, 4);
  ASSERT_EQ(diff.height, 3);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 4; ++x) {
      bool differs = (x == 1 && y == 1) || (x == 3 && y == 2);
      int brightest = brightest_channel(diff, x, y);
      EXPECT_TRUE(differs ? brightest >= 128 : brightest == 0)
          << x << "," << y << ": " << brightest;
    }
  }
  EXPECT_GT(diff.row(2)[3 * 3], diff.row(1)[1 * 3]);  // further along the ramp
}

TEST(DiffImage, ToleratedDifferencesStayDimmerThanCountedOnes) {
  Image a = filled(2, 1, 0);
  Image b = a;
  set_pixel(b, 0, 0, 0, 0, 40);
  set_pixel(b, 1, 0, 0, 0, 41);
  Image diff = diff_image(a, b, {.threshold = 40});
  EXPECT_GT(brightest_channel(diff, 0, 0), 0);
  EXPECT_LT(brightest_channel(diff, 0, 0), brightest_channel(diff, 1, 0));
  EXPECT_GE(brightest_channel(diff, 1, 0), 128);
}

TEST(DiffImage, IsEmptyWhenSizesDiffer) {
  EXPECT_EQ(diff_image(Image(2, 2), Image(3, 2), {}), Image());
}

}  // namespace
}  // namespace rayfarm
