// The model-file loader's fast path: from text straight to a checked Scene in one pass, with
// no parsed description in between and no allocation per attribute.
#pragma once

#include <cstddef>
#include <optional>
#include <string_view>

#include "rayfarm/scene.h"

namespace rayfarm {

// The scene of a plainly valid model file, or nullopt at the first thing that is not plainly
// valid (an error, or anything unusual): the caller then runs parse_model and build_scene,
// which find and explain every problem. Whenever it gives a scene, it is the scene those two
// would build (tests/model_fast_test.cpp and the model-parser fuzz target hold it to that).
// Files of `parallel_min` bytes or more are read in two parts on two threads (when the
// machine has two cores), with the same result.
inline constexpr std::size_t kFastParallelMin = 1 << 20;
std::optional<Scene> load_model_fast(std::string_view text,
                                     std::size_t parallel_min = kFastParallelMin);

}  // namespace rayfarm
