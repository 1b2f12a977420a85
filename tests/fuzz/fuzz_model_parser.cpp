// libFuzzer entry point for rayfarm::fuzz::model_parser.
#include "targets.h"

extern "C" int LLVMFuzzerTestOneInput(const unsigned char* data, unsigned long size) {
  return rayfarm::fuzz::model_parser(data, size);
}
