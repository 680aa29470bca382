#pragma once
namespace s2c {
inline constexpr const char* kVersion = "0.1.0";
}
