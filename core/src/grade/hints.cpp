// Hints that name the mistake behind a wrong image. Each detector tests one cause the way a
// TA would: the reference transformed (flipped, channels swapped) or rendered with another
// convention (rounding, profile, path cap, no reflections) matches the student's image where
// the reference does not; or rayfarm's record of what each pixel met (explain.h) shows the
// wrong pixels all lie in reflections, shadows, highlights or on one object, or are specks.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <string_view>

#include "rayfarm/explain.h"
#include "rayfarm/grade.h"
#include "rayfarm/schema.h"

namespace rayfarm::grading {
namespace {

using Alternative = std::function<std::optional<Image>(const RenderOptions&)>;

double bad_fraction(const Image& a, const Image& b, const TestSpec& t) {
  std::string error;
  auto m = compare_images(a, b, CompareOptions{t.threshold, t.neighborhood}, &error);
  return m ? m->differing_fraction : 1;
}

// Whether `candidate` (an image the student may have made instead) explains their image: it
// is that image exactly, or under the test's rules it is nearer to it than the reference
// (`base`, the reference's bad fraction) by far. Never one no nearer than the reference: on a
// test passed within its threshold, a render that changes nothing (no path cap where no path
// is that long) matched as well as the reference and was named as the mistake.
bool explains(const Image& candidate, const Image& mine, double base, const TestSpec& t) {
  if (candidate == mine) return true;  // (mine is not the reference: find_hints)
  const double c = bad_fraction(candidate, mine, t);
  return c < base && (c <= t.max_bad_fraction || (c < 0.02 && c <= base / 4));
}

template <class Map>
Image transformed(const Image& in, Map map) {
  Image out(in.width, in.height);
  for (int y = 0; y < in.height; ++y)
    for (int x = 0; x < in.width; ++x) {
      auto [sx, sy] = map(x, y);
      const std::uint8_t* p = in.row(sy) + 3 * sx;
      std::copy(p, p + 3, out.row(y) + 3 * x);
    }
  return out;
}

Image permuted(const Image& in, std::array<int, 3> order) {
  Image out(in.width, in.height);
  for (size_t i = 0; i < in.rgb.size(); i += 3)
    for (int c = 0; c < 3; ++c) out.rgb[i + c] = in.rgb[i + order[c]];
  return out;
}

bool one_colour(const Image& im) {
  for (size_t i = 3; i < im.rgb.size(); i += 3)
    if (!std::equal(im.rgb.begin() + i, im.rgb.begin() + i + 3, im.rgb.begin())) return false;
  return true;
}

std::string count_of(long long n, long long of) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%lld of the %lld wrong pixels (%.0f%%)", n, of,
                of ? 100.0 * n / of : 0.0);
  return buf;
}

std::string share(long long n, long long total) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.0f%%", total ? 100.0 * n / total : 0.0);
  return buf;
}

// The geometry and channel order: a transformed reference that matches says it all.
std::optional<Hint> layout_hint(const Image& ref, const Image& mine, const TestSpec& t, double base) {
  const int w = ref.width, h = ref.height;
  struct Candidate {
    const char* code;
    std::string message;
    Image image;
  };
  std::vector<Candidate> candidates;
  candidates.push_back({"upside_down",
                        "your image is upside down: an image file starts with its top row, which "
                        "is the world's row H-1; write the rows from y = H-1 down to 0",
                        transformed(ref, [&](int x, int y) { return std::pair{x, h - 1 - y}; })});
  candidates.push_back({"mirrored",
                        "your image is mirrored left to right: column x = 0 of the file is the "
                        "left edge of the screen, world x = 0",
                        transformed(ref, [&](int x, int y) { return std::pair{w - 1 - x, y}; })});
  candidates.push_back(
      {"rotated", "your image is turned upside down and mirrored (rotated 180 degrees): the file's "
                  "first pixel is the top left, world (0, H-1)",
       transformed(ref, [&](int x, int y) { return std::pair{w - 1 - x, h - 1 - y}; })});
  candidates.push_back({"red_blue_swapped",
                        "red and blue are swapped: a PPM stores each pixel as red, green, blue",
                        permuted(ref, {2, 1, 0})});
  for (std::array<int, 3> order :
       {std::array{1, 0, 2}, std::array{0, 2, 1}, std::array{1, 2, 0}, std::array{2, 0, 1}}) {
    const char* names = "RGB";
    candidates.push_back({"channels_swapped",
                          std::string("the colour channels are in the wrong order: your red, "
                                      "green and blue hold the reference's ") +
                              names[order[0]] + ", " + names[order[1]] + " and " + names[order[2]],
                          permuted(ref, order)});
  }
  for (const Candidate& c : candidates) {
    if (c.image == ref) continue;  // a symmetric image tells nothing
    if (explains(c.image, mine, base, t)) return Hint{c.code, c.message};
  }
  return std::nullopt;
}

// Every difference one level, one way: the conversion of a colour to a byte.
std::optional<Hint> rounding_hint(const Image& ref, const Image& mine, const RenderOptions& options,
                                  const Alternative& alternative) {
  long long up = 0, down = 0, other = 0;
  for (size_t i = 0; i < ref.rgb.size(); ++i) {
    const int d = mine.rgb[i] - ref.rgb[i];
    up += d == 1;
    down += d == -1;
    other += d > 1 || d < -1;
  }
  if (other > 0 || up + down == 0) return std::nullopt;
  const bool truncates = options.effective_rounding() == Rounding::truncate;
  std::string n = std::to_string(up + down);
  if (up > 0 && down > 0)
    return Hint{"off_by_one",
                "every difference is exactly one level, some up and some down (" + n +
                    " channels): the arithmetic differs slightly (float for double, or another "
                    "order of operations) near the edge between two byte values"};
  RenderOptions flipped = options;
  flipped.rounding = truncates ? Rounding::nearest : Rounding::truncate;
  bool exact = false, plausible = true;
  if (profile_conflict(flipped).empty())
    if (auto alt = alternative(flipped)) {
      exact = *alt == mine;
      // The other convention moves many channels; a student's image that shares few of those
      // moves (one channel of one pixel) is not explained by it.
      long long moved = 0, shared = 0;
      for (size_t i = 0; i < ref.rgb.size(); ++i) {
        moved += alt->rgb[i] != ref.rgb[i];
        shared += alt->rgb[i] != ref.rgb[i] && mine.rgb[i] == alt->rgb[i];
      }
      plausible = exact || 10 * shared >= 9 * moved;
    }
  const std::string confirmed = exact ? std::string(" Your image is exactly the reference made with "
                                                    "rounding=") +
                                            (truncates ? "nearest." : "truncate.")
                                      : "";
  if (up > 0 && truncates && plausible)
    return Hint{"rounding",
                "every difference is one level too bright (" + n +
                    " channels): you round to the nearest byte, (int)(255 * c + 0.5), where the "
                    "reference truncates, (int)(255 * c)." + confirmed};
  if (down > 0 && !truncates && plausible)
    return Hint{"truncation",
                "every difference is one level too dark (" + n +
                    " channels): you truncate, (int)(255 * c), where the reference rounds to the "
                    "nearest byte, (int)(255 * c + 0.5)." + confirmed};
  return Hint{"off_by_one", std::string("every difference is exactly one level ") +
                                (up > 0 ? "too bright" : "too dark") + " (" + n +
                                " channels): check how a colour becomes a byte (clamping to 1 "
                                "first, then 255 * c)"};
}

// Another convention rendered: the other profile, another path cap, no reflections.
std::optional<Hint> convention_hint(const Image& mine, const TestSpec& t,
                                    const RenderOptions& options, double base,
                                    const Alternative& alternative) {
  struct Try {
    const char* code;
    std::string message;
    RenderOptions options;
  };
  std::vector<Try> tries;
  RenderOptions other = options;
  if (options.profile == Profile::cpsc102) {
    other.profile = Profile::lecture;
    tries.push_back({"lecture_profile",
                     "your image matches the lecture's equation (profile lecture), not the course "
                     "program's (cpsc102): the course divides the whole colour (ambient, diffuse "
                     "and glint) by the ray's total path length, stops paths longer than 20 "
                     "units, and truncates to bytes",
                     other});
  } else {
    other.profile = Profile::cpsc102;
    tries.push_back({"cpsc102_profile",
                     "your image matches the course program's conventions (profile cpsc102) "
                     "where this test uses the lecture's equation (profile lecture)",
                     other});
  }
  const double cap = options.effective_max_dist();
  RenderOptions capped = options;
  if (std::isfinite(cap)) {
    capped.max_dist = std::numeric_limits<double>::infinity();
    tries.push_back({"path_cap",
                     "your image matches a render without a path cap: the reference shows the "
                     "background where a ray's total path is longer than " +
                         format_number(cap) + " units",
                     capped});
  } else {
    capped.max_dist = 20;
    tries.push_back({"path_cap",
                     "your image matches a render that stops paths longer than 20 units: the "
                     "reference has no path cap",
                     capped});
  }
  if (options.effective_max_depth() > 0) {
    RenderOptions flat = options;
    flat.max_depth = 0;
    tries.push_back({"no_reflections",
                     "your image matches a render without reflected or transmitted rays: trace "
                     "the reflected ray from each hit on a reflective material and add "
                     "specular * its colour",
                     flat});
  }
  for (const Try& tr : tries) {
    if (!profile_conflict(tr.options).empty() || tr.options == options) continue;
    std::optional<Image> alt = alternative(tr.options);
    if (!alt || alt->width != mine.width || alt->height != mine.height) continue;
    if (explains(*alt, mine, base, t)) return Hint{tr.code, tr.message};
  }
  return std::nullopt;
}

// Where the wrong pixels are, by what the reference's rays met there.
std::vector<Hint> region_hints(const Image& ref, const Image& mine, const TestSpec& t,
                               const RenderOptions& options, const Scene& scene, int threads) {
  const int w = ref.width, h = ref.height;
  const long long total = static_cast<long long>(w) * h;
  std::vector<std::uint8_t> wrong(static_cast<size_t>(total));
  long long n = 0;
  for (long long i = 0; i < total; ++i) {
    const std::uint8_t* a = ref.rgb.data() + 3 * i;
    const std::uint8_t* b = mine.rgb.data() + 3 * i;
    int d = 0;
    for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(a[c] - b[c]));
    wrong[i] = d > t.threshold;
    n += wrong[i];
  }
  std::vector<Hint> hints;
  if (n < 3) return hints;

  // Speckles: scattered wrong pixels (at most two wrong neighbours of eight) where the
  // reference is smooth. A wrong region is a solid patch; a wrong edge is not smooth.
  long long specks = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!wrong[static_cast<size_t>(y) * w + x]) continue;
      int wrong_near = 0;
      bool smooth = true;
      const std::uint8_t* p = ref.row(y) + 3 * x;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
          wrong_near += wrong[static_cast<size_t>(ny) * w + nx];
          const std::uint8_t* q = ref.row(ny) + 3 * nx;
          for (int c = 0; c < 3; ++c) smooth = smooth && std::abs(p[c] - q[c]) <= 8;
        }
      specks += wrong_near <= 2 && smooth;
    }
  if (n >= 5 && specks * 10 >= n * 6)
    hints.push_back({"speckles",
                     count_of(specks, n) +
                         " are scattered specks where the reference is smooth: a ray probably "
                         "meets the surface it starts from (a shadow or reflected ray hitting "
                         "its own object at t near 0, \"acne\"). Skip the object a ray leaves, "
                         "or start it a little off the surface"});

  std::string error;
  auto records = record_pixels(scene, options, threads, &error);
  if (!records || records->size() != static_cast<size_t>(total)) return hints;
  const std::vector<PixelRecord>& rec = *records;
  struct Region {
    const char* code;
    std::function<bool(long long)> in;
    std::string what;
    std::string advice;
  };
  auto flag = [&](int f) { return [&rec, f](long long i) { return (rec[i].flags & f) != 0; }; };
  // In order of preference where two cover the same pixels: the more specific cause first.
  std::vector<Region> regions = {
      {"shadows", flag(PixelRecord::shadow | PixelRecord::later_shadow),
       "depend on a shadow test (here or in what a reflection shows)",
       "check the shadow test: a ray from the hit point towards the light, blocked only by hits "
       "between the two, never by the point's own surface"},
      // Any glint term at all: a wrong exponent moves the highlight's edge far out.
      {"highlights",
       [&rec](long long i) {
         return rec[i].highlight_level > 0 ||
                (rec[i].flags & (PixelRecord::highlight | PixelRecord::later_highlight)) != 0;
       },
       "have a highlight (glint) term",
       "check the specular (glint) term: its vectors, its exponent, and that it uses the "
       "light's colour"},
      {"transmission", flag(PixelRecord::transmission), "look through a translucent object",
       "check the ray that goes on through the surface and how much of each colour it keeps"},
      {"reflections", flag(PixelRecord::reflection), "show a reflection",
       "check the reflected ray: R = D - 2 (N.D) N from the hit point, what it hits, and that "
       "specular * its colour is added"},
      {"path_cap", flag(PixelRecord::capped), "are on paths longer than max_dist",
       "check where paths stop: beyond the cap a ray gives the background"},
      {"background", [&](long long i) { return !(rec[i].flags & PixelRecord::hit); },
       "are where the ray meets nothing", "check the background colour and rays that miss everything"},
  };
  for (size_t k = 0; k < scene.objects.size(); ++k) {
    const Object& o = scene.objects[k];
    const int object = static_cast<int>(k);
    regions.push_back({"one_object", [&rec, object](long long i) { return rec[i].object == object; },
                       "are on " + std::string(entity_spec(o.kind).keyword) + " '" + o.name + "'",
                       "check its intersection test and its material"});
  }
  // The most specific cause whose region holds nearly all the wrong pixels is named, and
  // the object they are on, if one holds them: where to look, beside what to check.
  struct Found {
    const Region* region = nullptr;
    long long all = 0, wrong = 0;
  };
  Found cause, object;
  for (const Region& region : regions) {
    long long in_wrong = 0, in_all = 0;
    for (long long i = 0; i < total; ++i) {
      const bool in = region.in(i);
      in_all += in;
      in_wrong += in && wrong[i];
    }
    if (in_wrong * 10 < n * 9 || in_all * 4 > total * 3) continue;
    Found& slot = std::string_view(region.code) == "one_object" ? object : cause;
    if (!slot.region || in_all < slot.all) slot = {&region, in_all, in_wrong};
  }
  std::vector<Hint> found;
  for (const Found& f : {cause, object})
    if (f.region)
      found.push_back({f.region->code, count_of(f.wrong, n) + " " + f.region->what + " (" +
                                           share(f.all, total) + " of the image): " +
                                           f.region->advice});
  hints.insert(hints.end(), found.begin(), found.end());
  return hints;
}

}  // namespace

std::vector<Hint> find_hints(const Image& ref, const Image& mine, const TestSpec& test,
                             const RenderOptions& options, const Scene* scene,
                             const Alternative& alternative, int threads) {
  if (ref.width != mine.width || ref.height != mine.height || ref == mine) return {};
  if (one_colour(mine) && !one_colour(ref)) {
    const std::uint8_t* p = mine.rgb.data();
    return {{"blank_image", "your image is one colour, (" + std::to_string(p[0]) + ", " +
                                std::to_string(p[1]) + ", " + std::to_string(p[2]) +
                                "), everywhere: no ray hit anything, or nothing was written. "
                                "Check the camera (the eye, the screen at z = 0, the world size)"}};
  }
  const double base = bad_fraction(ref, mine, test);
  if (auto h = layout_hint(ref, mine, test, base)) return {*h};
  if (auto h = rounding_hint(ref, mine, options, alternative)) return {*h};
  if (auto h = convention_hint(mine, test, options, base, alternative)) return {*h};
  if (!scene) return {};
  return region_hints(ref, mine, test, options, *scene, threads);
}

}  // namespace rayfarm::grading
