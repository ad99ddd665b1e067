#pragma once
// A flat binary record of plain values, for the state a checkpoint carries (sim::World's
// save_state). Values are written as their bytes on this machine: a record is read back by the
// same build on the same kind of machine (a worker resuming a job), not exchanged between
// platforms. Reading checks every length against what is left and names what is short.
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "core/common/error.hpp"

namespace demcal {

class ByteWriter {
 public:
  template <class T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const char*>(&value);
    bytes_.append(p, sizeof(T));
  }
  template <class T>
  void put(const std::vector<T>& values) {
    static_assert(std::is_trivially_copyable_v<T>);
    put<std::uint64_t>(values.size());
    bytes_.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
  }
  void put(const std::string& text) {
    put<std::uint64_t>(text.size());
    bytes_.append(text);
  }
  /// put() under the name ByteReader reads with, so that one function listing a record's
  /// fields serves both directions.
  template <class T>
  void field(const T& value) {
    put(value);
  }
  std::string take() { return std::move(bytes_); }

 private:
  std::string bytes_;
};

class ByteReader {
 public:
  /// `what` names the record in errors ("checkpoint").
  ByteReader(std::string_view bytes, std::string what) : bytes_(bytes), what_(std::move(what)) {}

  template <class T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    T value;
    std::memcpy(&value, take(sizeof(T)), sizeof(T));
    return value;
  }
  template <class T>
  void get(T& value) {
    value = get<T>();
  }
  template <class T>
  void get(std::vector<T>& values) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto n = get<std::uint64_t>();
    if (n > left() / sizeof(T)) short_of(n * sizeof(T));
    values.resize(n);
    if (n) std::memcpy(values.data(), take(n * sizeof(T)), n * sizeof(T));
  }
  void get(std::string& text) {
    const auto n = get<std::uint64_t>();
    text.assign(take(n), n);
  }
  template <class T>
  void field(T& value) {
    get(value);
  }
  std::size_t left() const { return bytes_.size() - at_; }
  /// Throws unless every byte was read.
  void expect_end() const {
    if (left() != 0)
      throw InputError(what_, std::to_string(left()) + " bytes left over after its last field");
  }

 private:
  const char* take(std::size_t n) {
    if (n > left()) short_of(n);
    const char* p = bytes_.data() + at_;
    at_ += n;
    return p;
  }
  [[noreturn]] void short_of(std::size_t n) const {
    throw InputError(what_, "truncated: a field needs " + std::to_string(n) + " bytes at byte " +
                                std::to_string(at_) + ", " + std::to_string(left()) + " left");
  }
  std::string_view bytes_;
  std::size_t at_ = 0;
  std::string what_;
};

}  // namespace demcal
