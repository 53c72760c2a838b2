// Bounds-checked little-endian reads from a byte buffer (the .vdb readers of
// vdb_io.cc and vdb_payload.cc). Every read checks the bytes left before it
// copies anything and throws samp::Error naming the context and the field.
// Not thread-safe; the buffer must outlive the reader.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>

#include "libsamp/core/error.h"

namespace samp {

class ByteReader {
 public:
  // Reads `bytes` up to `end` (at most its size); errors start with `context`
  // (a file name, or "file: grid 'g'").
  ByteReader(const std::string& bytes, const std::string& context, size_t end = size_t(-1))
      : bytes_(bytes), context_(context), end_(end < bytes.size() ? end : bytes.size()) {}

  size_t pos() const { return pos_; }
  size_t end() const { return end_; }
  size_t remaining() const { return end_ - pos_; }
  const std::string& context() const { return context_; }
  // Moves the end of the readable range (at most the buffer's size, at least pos()).
  void SetEnd(size_t end) {
    end_ = end < bytes_.size() ? end : bytes_.size();
    if (end_ < pos_) end_ = pos_;
  }

  void Seek(int64_t pos, const char* what) {
    SAMP_CHECK(pos >= 0 && uint64_t(pos) <= end_)
        << context_ << ": " << what << " points to byte " << pos << " of a " << end_
        << "-byte " << (end_ == bytes_.size() ? "file" : "range") << " (truncated or corrupt)";
    pos_ = size_t(pos);
  }
  template <typename T>
  T Read(const char* what) {
    Need(sizeof(T), what);
    T value;
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  // `n` values of T into `out`.
  template <typename T>
  void ReadArray(T* out, size_t n, const char* what) {
    SAMP_CHECK(n <= remaining() / sizeof(T))
        << context_ << ": truncated or corrupt file: " << what << " at byte " << pos_ << " needs "
        << n << " x " << sizeof(T) << " bytes, " << remaining() << " remain";
    if (n == 0) return;  // `out` may be null
    std::memcpy(out, bytes_.data() + pos_, n * sizeof(T));
    pos_ += n * sizeof(T);
  }
  // A uint32 length and that many bytes (OpenVDB's writeString).
  std::string ReadString(const char* what) { return ReadBytes(Read<uint32_t>(what), what); }
  std::string ReadBytes(uint64_t n, const char* what) {
    Need(n, what);
    std::string value = bytes_.substr(pos_, size_t(n));
    pos_ += size_t(n);
    return value;
  }
  // The next `n` bytes in place (valid as long as the buffer).
  const char* Take(uint64_t n, const char* what) {
    Need(n, what);
    const char* data = bytes_.data() + pos_;
    pos_ += size_t(n);
    return data;
  }
  void Skip(uint64_t n, const char* what) {
    Need(n, what);
    pos_ += size_t(n);
  }

 private:
  void Need(uint64_t n, const char* what) const {
    SAMP_CHECK(n <= end_ - pos_)
        << context_ << ": truncated or corrupt file: " << what << " at byte " << pos_ << " needs "
        << n << " bytes, " << (end_ - pos_) << " remain";
  }

  const std::string& bytes_;
  const std::string context_;
  size_t end_;
  size_t pos_ = 0;
};

}  // namespace samp
