// libFuzzer entry point for rayfarm::fuzz::http_request.
#include "targets.h"

extern "C" int LLVMFuzzerTestOneInput(const unsigned char* data, unsigned long size) {
  return rayfarm::fuzz::http_request(data, size);
}
