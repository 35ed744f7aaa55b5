/// \file Scalar.hpp
/// \brief Tags for the arithmetic types and operations a backend reduces natively.
///
/// The typed front end (pik::BasicComm) maps each C++ arithmetic type to a
/// ScalarKind, so a backend needs one reduction entry point instead of one per type.
#pragma once

#include <concepts>
#include <cstdint>
#include <type_traits>

namespace pik::comm {

/// The element-wise reductions every backend provides.
enum class ReduceOp { sum, min, max };

/// Arithmetic element types a backend reduces natively.
enum class ScalarKind { i8, u8, i16, u16, i32, u32, i64, u64, f32, f64, f80 };

/// Types that BasicComm reduces element-wise (integers and floating point; not bool).
template <class T>
concept Reducible = std::is_arithmetic_v<T> && !std::same_as<T, bool>;

/// The ScalarKind of a reducible type, chosen by size and signedness so that
/// `long` and `long long` map to the same 64-bit kind.
template <Reducible T>
constexpr ScalarKind scalar_kind() {
  if constexpr (std::is_floating_point_v<T>) {
    if constexpr (sizeof(T) == 4) return ScalarKind::f32;
    else if constexpr (sizeof(T) == 8) return ScalarKind::f64;
    else return ScalarKind::f80;
  } else if constexpr (std::is_signed_v<T>) {
    if constexpr (sizeof(T) == 1) return ScalarKind::i8;
    else if constexpr (sizeof(T) == 2) return ScalarKind::i16;
    else if constexpr (sizeof(T) == 4) return ScalarKind::i32;
    else return ScalarKind::i64;
  } else {
    if constexpr (sizeof(T) == 1) return ScalarKind::u8;
    else if constexpr (sizeof(T) == 2) return ScalarKind::u16;
    else if constexpr (sizeof(T) == 4) return ScalarKind::u32;
    else return ScalarKind::u64;
  }
}

}  // namespace pik::comm
