#include <charconv>

#include <fmt/format.h>

#include "s2c/acquire/frame_source.h"
#include "s2c/acquire/sources.h"

namespace s2c {

std::optional<std::string> DropMonitor::count(bool dropped, SteadyTime now) {
  if (!started_ || std::chrono::duration<double>(now - window_start_).count() > window_s_) {
    started_ = true;
    window_start_ = now;
    seen_ = dropped_ = 0;
    warned_ = false;
  }
  ++seen_;
  if (dropped) ++dropped_;
  // At least 20 frames before judging, so one bad frame at start-up is not "100% dropped".
  if (warned_ || seen_ < 20 || dropped_ <= threshold_ * seen_) return std::nullopt;
  warned_ = true;
  return fmt::format("{} of the last {} frames dropped ({:.0f}%) within {:.0f} s: check the cable, USB port and "
                     "lighting", dropped_, seen_, 100.0 * dropped_ / seen_, window_s_);
}

namespace {

std::uint16_t parse_hex16(const std::string& text, const std::string& spec) {
  unsigned v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v, 16);
  if (text.empty() || text.size() > 4 || ec != std::errc() || end != text.data() + text.size())
    throw InvalidInput(fmt::format("--from {}: '{}' is not a 4-digit hex USB id (e.g. usb:1209:0001)", spec, text));
  return static_cast<std::uint16_t>(v);
}

}  // namespace

SourceSpec parse_source_spec(const std::string& text) {
  const auto colon = text.find(':');
  const std::string kind = text.substr(0, colon), rest = colon == std::string::npos ? "" : text.substr(colon + 1);
  SourceSpec s;
  if (kind == "v4l2" && !rest.empty()) {
    s.kind = SourceSpec::Kind::v4l2;
    s.path = rest;
  } else if (kind == "replay" && !rest.empty()) {
    s.kind = SourceSpec::Kind::replay;
    s.path = rest;
  } else if (kind == "usb" && rest.find(':') != std::string::npos) {
    s.kind = SourceSpec::Kind::usb;
    const auto c = rest.find(':');
    s.vendor = parse_hex16(rest.substr(0, c), text);
    s.product = parse_hex16(rest.substr(c + 1), text);
  } else {
    throw InvalidInput(fmt::format("--from '{}': expected v4l2:/dev/videoN, usb:VID:PID (hex) or replay:STREAM_DIR",
                                   text));
  }
  return s;
}

}  // namespace s2c
