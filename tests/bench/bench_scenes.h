// Scenes for the benchmarks, made in memory so that runs need no generated files.
#pragma once

#include <cstdint>
#include <string>

#include "rayfarm/scene.h"

namespace rayfarm::bench {

// `count` random small spheres in front of the lecture camera (800x600, window 8x6, eye
// at 4 3 5), a floor, two lights, one material in four mirror-like. Same seed, same scene.
Scene random_spheres(int count, std::uint64_t seed = 1);

// The same scene as model-file text (what `rayfarm render` would read).
std::string random_spheres_text(int count, std::uint64_t seed = 1);

// A bundled scene by path relative to the source tree; throws when it does not load.
Scene load_bundled(const std::string& relative_path);

}  // namespace rayfarm::bench
