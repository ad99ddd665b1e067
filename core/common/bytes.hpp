#pragma once
// A flat binary record of plain values, for the state a checkpoint carries (sim::World's
// save_state, the stages of a lab test). Values are written as their bytes on this machine: a
// record is read back by the same build on the same kind of machine (a worker resuming a job),
// not exchanged between platforms. Reading checks every length against what is left and names
// what is short.
//
// field() is the one name both directions use, so that one function listing a record's fields
// serves saving and restoring: plain values and vectors of them as their bytes, strings, vectors
// and maps element by element, and any other type through the function `record_fields(a, value)`
// found beside the type (one template for a ByteWriter and a ByteReader, `value` const or not:
// declare it with RecordOf).
#include <concepts>
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "core/common/error.hpp"

namespace demcal {

/// `P` is `T` or `const T`: the value parameter of a record_fields overload for T.
template <class P, class T>
concept RecordOf = std::same_as<std::remove_const_t<P>, T>;

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
  template <class T>
  void field(const T& value) {
    if constexpr (std::is_trivially_copyable_v<T>)
      put(value);
    else
      record_fields(*this, value);
  }
  void field(const std::string& text) { put(text); }
  template <class T>
  void field(const std::vector<T>& values) {
    if constexpr (std::is_trivially_copyable_v<T>)
      put(values);
    else
      each(values, [this](const T& value) { field(value); });
  }
  /// The count of `values`, then `item(value)` for each: a vector of elements whose fields are
  /// listed in place (ByteReader::each reads them back).
  template <class T, class F>
  void each(const std::vector<T>& values, F item) {
    put<std::uint64_t>(values.size());
    for (const T& value : values) item(value);
  }
  template <class K, class V>
  void field(const std::map<K, V>& values) {
    put<std::uint64_t>(values.size());
    for (const auto& [key, value] : values) {
      field(key);
      field(value);
    }
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
    static_assert(std::is_trivially_copyable_v<T>);
    std::memcpy(&value, take(sizeof(T)), sizeof(T));
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
    if constexpr (std::is_trivially_copyable_v<T>)
      get(value);
    else
      record_fields(*this, value);
  }
  void field(std::string& text) { get(text); }
  template <class T>
  void field(std::vector<T>& values) {
    if constexpr (std::is_trivially_copyable_v<T>)
      get(values);
    else
      each(values, [this](T& value) { field(value); });
  }
  /// Reads what ByteWriter::each wrote: `values` becomes that many default elements, each
  /// then handed to `item`.
  template <class T, class F>
  void each(std::vector<T>& values, F item) {
    values.clear();
    values.resize(count());
    for (T& value : values) item(value);
  }
  template <class K, class V>
  void field(std::map<K, V>& values) {
    values.clear();
    for (auto n = count(); n > 0; --n) {
      K key;
      V value;
      field(key);
      field(value);
      values.insert_or_assign(std::move(key), std::move(value));
    }
  }
  std::size_t left() const { return bytes_.size() - at_; }
  /// Throws unless every byte was read.
  void expect_end() const {
    if (left() != 0)
      throw InputError(what_, std::to_string(left()) + " bytes left over after its last field");
  }

 private:
  /// The count of elements that follows, each at least one byte.
  std::uint64_t count() {
    const auto n = get<std::uint64_t>();
    if (n > left()) short_of(n);
    return n;
  }
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
