// One libFuzzer executable per target: S2C_FUZZ_TARGET names the function of targets.h.
#include <cstddef>
#include <cstdint>

#include "targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  s2c::fuzz::S2C_FUZZ_TARGET(data, size);
  return 0;
}
