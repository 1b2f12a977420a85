// libFuzzer entry point for rayfarm::fuzz::json_scene.
#include "targets.h"

extern "C" int LLVMFuzzerTestOneInput(const unsigned char* data, unsigned long size) {
  return rayfarm::fuzz::json_scene(data, size);
}
