#pragma once
// NumPy .npy and .npz files (the ground truth of the shared data sets is stored in them).
// .npy: magic "\x93NUMPY", version 1.0/2.0/3.0, a Python-dict header ('descr', 'fortran_order',
// 'shape'), then the raw C-order data. .npz: a zip archive of "<key>.npy" entries (stored or
// deflated, as numpy.savez / savez_compressed write them), read and written with libzip.
// Supported dtypes: <f4 <f8 |u1 |i1 |b1 <u2 <i2 <u4 <i4 <u8 <i8 and <U<n> (UTF-32 strings);
// little-endian only (a big-endian array is an error naming the file). Fortran order is an
// error: callers assume C order (row-major, last index fastest).

#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include "src/core/logging.h"

namespace hairmvs {

// The numpy descr of a C++ element type: "<f4" for float, "|u1" for uint8_t...
template <typename T>
std::string NpyDtypeOf();

struct NpyArray {
  std::string dtype;           // numpy descr, e.g. "<f4", "|u1", "<i8", "<U9"
  std::vector<size_t> shape;   // C order; empty = scalar (one element)
  std::vector<char> data;      // NumElements() * ItemSize() bytes

  size_t NumElements() const;
  // Bytes per element, from the dtype (4 for "<f4", 4*n for "<U<n>").
  size_t ItemSize() const;
  bool IsString() const { return dtype.size() > 1 && dtype[1] == 'U'; }
  // Signed or unsigned integers, or booleans.
  bool IsInteger() const {
    return dtype.size() > 1 && (dtype[1] == 'i' || dtype[1] == 'u' || dtype[1] == 'b');
  }

  // Typed view; the dtype must be exactly NpyDtypeOf<T>() (CHECK: a caller bug otherwise).
  template <typename T>
  const T* Data() const {
    CHECK_EQ(dtype, NpyDtypeOf<T>()) << "NpyArray::Data<T>() with the wrong element type";
    return reinterpret_cast<const T*>(data.data());
  }
  template <typename T>
  T* Data() {
    CHECK_EQ(dtype, NpyDtypeOf<T>()) << "NpyArray::Data<T>() with the wrong element type";
    return reinterpret_cast<T*>(data.data());
  }
  // All elements converted to T (any numeric dtype; bool as 0/1). Throws hairmvs::Error for a
  // string array. `what` names the array in that message.
  template <typename T>
  std::vector<T> ToVector(const std::string& what = "array") const;
  // Element i as double (numeric dtypes).
  double AsDouble(size_t i) const;
  // The elements of a <U<n> array, UTF-32 -> UTF-8, trailing NULs removed. Throws
  // hairmvs::Error for another dtype; `what` names the array in that message.
  std::vector<std::string> Strings(const std::string& what = "array") const;

  template <typename T>
  static NpyArray FromVector(const std::vector<T>& values, std::vector<size_t> shape = {}) {
    static_assert(std::is_arithmetic_v<T>, "numeric element types only");
    NpyArray array;
    array.dtype = NpyDtypeOf<T>();
    array.shape = shape.empty() ? std::vector<size_t>{values.size()} : std::move(shape);
    CHECK_EQ(array.NumElements(), values.size());
    const char* bytes = reinterpret_cast<const char*>(values.data());
    array.data.assign(bytes, bytes + values.size() * sizeof(T));
    return array;
  }
  template <typename T>
  static NpyArray Scalar(T value) {
    NpyArray array = FromVector(std::vector<T>{value}, {});
    array.shape.clear();
    return array;
  }
  // A 1-D <U<n> array, n = the longest string (in code points, at least 1).
  static NpyArray FromStrings(const std::vector<std::string>& strings);
};

// Parses / formats a whole .npy file held in memory. `source` names it in error messages.
NpyArray ParseNpy(const char* bytes, size_t size, const std::string& source);
std::string FormatNpy(const NpyArray& array);

// Throws hairmvs::Error naming the file: missing, not a .npy/.npz, truncated, Fortran order,
// unsupported dtype, payload size not matching the shape.
NpyArray ReadNpy(const std::string& path);
std::map<std::string, NpyArray> ReadNpz(const std::string& path);
// Written atomically. WriteNpz deflates every entry ("<key>.npy"), like savez_compressed.
void WriteNpy(const std::string& path, const NpyArray& array);
void WriteNpz(const std::string& path, const std::map<std::string, NpyArray>& arrays);

// Looks up `key` in an archive read from `path`; throws naming both when it is missing.
const NpyArray& NpzEntry(const std::map<std::string, NpyArray>& arrays, const std::string& key,
                         const std::string& path);

template <> inline std::string NpyDtypeOf<float>() { return "<f4"; }
template <> inline std::string NpyDtypeOf<double>() { return "<f8"; }
template <> inline std::string NpyDtypeOf<uint8_t>() { return "|u1"; }
template <> inline std::string NpyDtypeOf<int8_t>() { return "|i1"; }
template <> inline std::string NpyDtypeOf<bool>() { return "|b1"; }
template <> inline std::string NpyDtypeOf<uint16_t>() { return "<u2"; }
template <> inline std::string NpyDtypeOf<int16_t>() { return "<i2"; }
template <> inline std::string NpyDtypeOf<uint32_t>() { return "<u4"; }
template <> inline std::string NpyDtypeOf<int32_t>() { return "<i4"; }
template <> inline std::string NpyDtypeOf<uint64_t>() { return "<u8"; }
template <> inline std::string NpyDtypeOf<int64_t>() { return "<i8"; }

template <typename T>
std::vector<T> NpyArray::ToVector(const std::string& what) const {
  THROW_IF(IsString(), what << ": expected a numeric array, found dtype " << dtype);
  const size_t n = NumElements();
  std::vector<T> out(n);
  if (dtype == NpyDtypeOf<T>()) {
    if (n > 0) std::memcpy(out.data(), data.data(), n * sizeof(T));
    return out;
  }
  for (size_t i = 0; i < n; ++i) out[i] = static_cast<T>(AsDouble(i));
  return out;
}

}  // namespace hairmvs
