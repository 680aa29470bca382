#pragma once
/// \file File-system helpers every command uses: atomic output, input protection, hashing.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace s2c {

/// A temporary file beside `target` that becomes `target` on commit() (rename is atomic on
/// POSIX within one file system). Destroyed without commit, it removes the temporary file,
/// so a failed run leaves nothing behind. The temporary name keeps the target's extension
/// because writers choose the format by extension.
class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path target);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::filesystem::path& temp_path() const { return temp_; }
  const std::filesystem::path& target() const { return target_; }
  /// fsyncs the temporary file and renames it onto the target. \throw IoError
  void commit();

 private:
  std::filesystem::path target_, temp_;
  bool committed_ = false;
};

/// Output written piece by piece to an AtomicFile. The disk starts writing each few megabytes as
/// they come (sync_file_range), so the fsync of commit() waits for the last ones only: a 17 MB
/// features.json spent 20 ms there after its last byte.
class AtomicStream {
 public:
  /// \throw IoError if the temporary file cannot be created.
  explicit AtomicStream(std::filesystem::path target);
  ~AtomicStream();
  AtomicStream(const AtomicStream&) = delete;
  AtomicStream& operator=(const AtomicStream&) = delete;

  /// Appends `piece`. \throw IoError
  void write(std::string_view piece);
  /// As AtomicFile::commit. \throw IoError
  void commit();

 private:
  void close_file();

  AtomicFile file_;
  int fd_ = -1;
  std::uint64_t written_ = 0, flushed_ = 0;  ///< bytes written; bytes handed to the disk
};

/// Writes `content` to `path` atomically. \throw IoError
void write_file_atomic(const std::filesystem::path& path, const std::string& content);

/// Reads a whole file. \throw IoError if it cannot be opened or read.
std::string read_file(const std::filesystem::path& path);

/// \throw InvalidInput if `output` names the same file as `input` (inputs are never modified).
void refuse_same_file(const std::filesystem::path& input, const std::filesystem::path& output);

/// Lower-case hex SHA-256 of a file's bytes. \throw IoError
std::string sha256_file(const std::filesystem::path& path);
/// Lower-case hex SHA-256 of a byte string.
std::string sha256_bytes(const std::string& bytes);

}  // namespace s2c
