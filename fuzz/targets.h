#pragma once
// The fuzz targets' bodies: one function per parser, fed raw bytes. Each must return normally
// for any input: the errors a parser may raise for bad input (InvalidInput, IoError) are
// caught here; anything else (a crash, another exception, a sanitizer report, a hang) is a bug.
// Used by the libFuzzer executables (fuzz_main.cpp) and by the regression test that replays
// fuzz/regressions/ and the seed corpora in every normal test run.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace s2c::fuzz {

using Target = void (*)(const std::uint8_t* data, std::size_t size);

/// PLY / STL / OBJ / OFF / VTK through read_soup: the first byte picks the extension.
void mesh(const std::uint8_t* data, std::size_t size);
/// PCD through the reconstruct stage's cloud reader (header check, then PCL).
void pcd(const std::uint8_t* data, std::size_t size);
/// A stream directory: stream.yaml, depth.txt, poses.txt and one frame PNG, separated by "\n%%\n".
void stream(const std::uint8_t* data, std::size_t size);
/// features.json text.
void features_json(const std::uint8_t* data, std::size_t size);
/// An edit script: parsed, then run on a small plate with its features.
void edit_script(const std::uint8_t* data, std::size_t size);
/// A USB profile packet, then the same bytes as a Z16 frame and through the sweep assembler.
void usb_profile(const std::uint8_t* data, std::size_t size);

struct NamedTarget {
  const char* name;
  Target run;
};
const std::vector<NamedTarget>& all_targets();

}  // namespace s2c::fuzz
