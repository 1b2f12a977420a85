// libFuzzer entry point for rayfarm::fuzz::image_decode.
#include "targets.h"

extern "C" int LLVMFuzzerTestOneInput(const unsigned char* data, unsigned long size) {
  return rayfarm::fuzz::image_decode(data, size);
}
