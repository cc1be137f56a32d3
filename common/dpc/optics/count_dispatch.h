#pragma once
// Compile-time loop counts for the common small cases.
//
// The real-time kernels loop over 3 or 4 stages (the paper's devices) far more often than over
// anything else; with a runtime count those loops pay for alias checks, vectorization prologues
// and loop control that cost more than the arithmetic. DispatchCount calls f with
// std::integral_constant<int, n> for n = 3 and 4, and with 0 ("use the runtime count")
// otherwise, so one kernel body serves every count and the common ones unroll fully:
//
//   DispatchCount(n, [&](auto fixed) {
//     const int count = FixedOr(fixed, n);
//     for (int i = 0; i < count; ++i) …
//   });

#include <type_traits>
#include <utility>

namespace dpc {

template <typename F>
inline decltype(auto) DispatchCount(int n, F&& f) {
  switch (n) {
    case 3: return f(std::integral_constant<int, 3>{});
    case 4: return f(std::integral_constant<int, 4>{});
    default: return f(std::integral_constant<int, 0>{});
  }
}

/// The compile-time count if there is one, else the runtime `n`.
template <int kFixed>
constexpr int FixedOr(std::integral_constant<int, kFixed>, int n) {
  return kFixed > 0 ? kFixed : n;
}

/// Calls f(std::integral_constant<int, i>) for i = 0 … kCount − 1, in order: a loop unrolled by
/// the compiler in any case, whose body may use i as a constant expression (an array index of
/// known value keeps arrays in registers, a template argument selects code per iteration).
template <int kCount, typename F>
[[gnu::always_inline]] inline void ForEachIndex(F&& f) {
  [&]<int... kIndex>(std::integer_sequence<int, kIndex...>) {
    (f(std::integral_constant<int, kIndex>{}), ...);
  }(std::make_integer_sequence<int, kCount>{});
}

}  // namespace dpc
