#include "s2c/acquire/recorder.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "s2c/core/errors.h"

namespace fs = std::filesystem;

namespace s2c {
namespace {

/// An I/O failure with the errno that caused it, so ENOSPC can be told from the rest.
struct WriteFailure {
  int err;
  std::string what;
};

void write_all(int fd, const char* data, std::size_t n, const std::string& what) {
  while (n > 0) {
    const ssize_t w = ::write(fd, data, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      throw WriteFailure{errno, what};
    }
    data += w;
    n -= static_cast<std::size_t>(w);
  }
}

int open_append(const fs::path& p) {
  const int fd = ::open(p.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) throw IoError(fmt::format("{}: cannot create: {}", p.string(), std::strerror(errno)));
  return fd;
}

void sync_directory(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

Recorder::Recorder(fs::path dir, const StreamInfo& info, RecorderOptions options)
    : dir_(std::move(dir)), info_(info), options_(std::move(options)) {
  if (fs::exists(dir_) && (!fs::is_directory(dir_) || !fs::is_empty(dir_)))
    throw InvalidInput(fmt::format("{}: exists and is not an empty directory; a recording never overwrites, choose "
                                   "another --out", dir_.string()));
  std::error_code ec;
  fs::create_directories(dir_ / "depth", ec);
  if (ec) throw IoError(fmt::format("{}: cannot create: {}", dir_.string(), ec.message()));
  try {
    // stream.yaml first: a recording cut short at any point is still a stream that reads.
    write_stream_yaml(dir_ / "stream.yaml", info_);
    index_fd_ = open_append(dir_ / "depth.txt");
    const std::string header = kIndexHeader;
    write_all(index_fd_, header.data(), header.size(), "depth.txt");
    index_bytes_ = header.size();
  } catch (const WriteFailure& f) {
    if (index_fd_ >= 0) ::close(index_fd_);
    fs::remove_all(dir_, ec);
    throw IoError(fmt::format("{}: cannot start the recording: {}: {}", dir_.string(), f.what, std::strerror(f.err)));
  } catch (...) {
    if (index_fd_ >= 0) ::close(index_fd_);
    fs::remove_all(dir_, ec);
    throw;
  }
  writer_ = std::thread([this] { writer_loop(); });
}

Recorder::~Recorder() {
  if (!finished_) {
    try {
      finish();
    } catch (const std::exception& e) {
      spdlog::error("{}: finishing the recording: {}", dir_.string(), e.what());
    }
  }
}

bool Recorder::add(Frame frame) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (options_.wait_when_full)
    cv_.wait(lock, [&] { return queue_.size() < options_.queue_frames || summary_.write_error || closing_; });
  if (summary_.write_error || closing_) return false;
  if (queue_.size() >= options_.queue_frames) {
    ++summary_.dropped_queue;
    return false;
  }
  queue_.push_back(std::move(frame));
  cv_.notify_all();
  return true;
}

std::uint64_t Recorder::kept() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return summary_.kept;
}

bool Recorder::failed() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return summary_.write_error.has_value();
}

void Recorder::writer_loop() {
  for (;;) {
    Frame f;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [&] { return closing_ || !queue_.empty(); });
      if (queue_.empty()) return;
      f = std::move(queue_.front());
      queue_.pop_front();
    }
    cv_.notify_all();  // room for a waiting add()
    try {
      write_frame(f);
    } catch (const WriteFailure& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      summary_.write_error = fmt::format("{}: {}", e.what, std::strerror(e.err));
      queue_.clear();  // nothing after a failed frame can be written either
      cv_.notify_all();
      return;
    }
  }
}

void Recorder::write_frame(const Frame& f) {
  const std::uint64_t n = kept();
  const std::string name = fmt::format("depth/{:06d}.png", n);
  const fs::path file = dir_ / name;
  const std::string png = encode_depth_png(f.image);
  const int fd = options_.open_frame_file ? options_.open_frame_file(file)
                                          : ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw WriteFailure{errno, name};
  try {
    write_all(fd, png.data(), png.size(), name);
    if (options_.sync_each_frame && ::fdatasync(fd) < 0 && errno != EINVAL) throw WriteFailure{errno, name};
    if (::close(fd) < 0) {
      const int e = errno;
      throw WriteFailure{e, name};
    }
  } catch (const WriteFailure&) {
    ::close(fd);
    std::error_code ec;
    fs::remove(file, ec);  // a frame that is not complete is not kept
    throw;
  }
  // Only now does the frame exist for a reader: its index line follows its data.
  const std::string line = index_line({f.timestamp, name, 0});
  const std::string pose = f.pose ? pose_line({f.timestamp, *f.pose}, info_.pose_unit_mm) : std::string();
  try {
    if (f.pose) {
      if (poses_fd_ < 0) {
        poses_fd_ = open_append(dir_ / "poses.txt");
        const std::string header = kPosesHeader;
        write_all(poses_fd_, header.data(), header.size(), "poses.txt");
        poses_bytes_ = header.size();
      }
      write_all(poses_fd_, pose.data(), pose.size(), "poses.txt");
    }
    write_all(index_fd_, line.data(), line.size(), "depth.txt");
  } catch (const WriteFailure&) {
    // Cut partly written lines off, so the index and the poses list only complete frames.
    if (::ftruncate(index_fd_, static_cast<off_t>(index_bytes_)) < 0) spdlog::error("depth.txt: cannot truncate");
    if (poses_fd_ >= 0 && ::ftruncate(poses_fd_, static_cast<off_t>(poses_bytes_)) < 0)
      spdlog::error("poses.txt: cannot truncate");
    std::error_code ec;
    fs::remove(file, ec);
    throw;
  }
  index_bytes_ += line.size();
  poses_bytes_ += pose.size();
  std::lock_guard<std::mutex> lock(mutex_);
  ++summary_.kept;
}

RecordSummary Recorder::finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (finished_) return summary_;
    closing_ = true;
  }
  cv_.notify_all();
  if (writer_.joinable()) writer_.join();
  for (int* fd : {&index_fd_, &poses_fd_}) {
    if (*fd < 0) continue;
    if (::fsync(*fd) < 0 && !summary_.write_error)
      summary_.write_error = fmt::format("fsync: {}", std::strerror(errno));
    ::close(*fd);
    *fd = -1;
  }
  sync_directory(dir_ / "depth");
  sync_directory(dir_);
  finished_ = true;
  return summary_;
}

}  // namespace s2c
