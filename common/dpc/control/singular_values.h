#pragma once
// The singular values σ_max ≥ σ_min of a reduced task Jacobian A (d × n, d ≤ 2), evaluated on
// demand. The control loop never needs them, yet computing them takes a chain of square roots
// and a division that would hold up the loop; so the real-time path stores what determines them
// (the Gram matrix G = AAᵀ, or the values themselves when a factorization produced them) and
// only a reader (diagnostics, statistics, the status topic) pays for the roots.
//
//   d = 2 from G: λ1 = tr/2 + √((g11 − g22)²/4 + g12²), λ2 = det G / λ1 (no cancellation),
//                 σ = √λ. Use only with an accurate det G (a well-conditioned G, or det
//                 computed otherwise).
//   d = 1 from G: σ_max = σ_min = √g.

#include <cmath>

namespace dpc {

class SingularValues {
 public:
  SingularValues() = default;

  static SingularValues FromGram(double g11, double g22, double g12, double det) {
    SingularValues s;
    s.kind_ = Kind::kGram2;
    s.a_ = g11;
    s.b_ = g22;
    s.c_ = g12;
    s.d_ = det;
    return s;
  }
  static SingularValues FromGram(double g) {
    SingularValues s;
    s.kind_ = Kind::kGram1;
    s.a_ = g;
    return s;
  }
  static SingularValues Exact(double sigma_max, double sigma_min) {
    SingularValues s;
    s.kind_ = Kind::kExact;
    s.a_ = sigma_max;
    s.b_ = sigma_min;
    return s;
  }

  double max() const {
    switch (kind_) {
      case Kind::kGram2: return std::sqrt(LargestEigenvalue());
      case Kind::kGram1: return std::sqrt(a_);
      case Kind::kExact: return a_;
    }
    return 0.0;
  }
  double min() const { return kind_ == Kind::kExact ? b_ : std::sqrt(min_squared()); }
  /// σ_min² (= λ2 of G; one square root and one division from the Gram matrix).
  double min_squared() const {
    switch (kind_) {
      case Kind::kGram2: {
        // λ2 = 2·det / (tr + √((g11 − g22)² + 4 g12²)): the stable root of λ² − tr·λ + det.
        const double denominator = a_ + b_ + std::sqrt((a_ - b_) * (a_ - b_) + 4.0 * c_ * c_);
        return denominator > 0.0 ? 2.0 * d_ / denominator : 0.0;
      }
      case Kind::kGram1: return a_;
      case Kind::kExact: return b_ * b_;
    }
    return 0.0;
  }
  /// Whether σ_min² may be below `bound` (no root, no division: λ2 = det/λ1 ≥ det/tr since
  /// λ1 ≤ tr, so det ≥ bound·tr rules it out). Callers looking for a minimum need min_squared()
  /// only when this is true.
  bool MayBeBelow(double bound) const {
    switch (kind_) {
      case Kind::kGram2: return GramMayBeBelow(a_, b_, d_, bound);
      case Kind::kGram1: return a_ < bound;
      case Kind::kExact: return b_ * b_ < bound;
    }
    return true;
  }
  /// Whether σ_min < ratio·σ_max (0 < ratio ≤ 1), decided exactly without roots: with
  /// q = ratio², λ2/λ1 < q ⇔ det/tr² < q/(1 + q)² (x/(1 + x)² increases on [0, 1]).
  bool IsBelowRatio(double ratio) const {
    switch (kind_) {
      case Kind::kGram2: return GramIsBelowRatio(a_, b_, d_, ratio);
      case Kind::kGram1: return false;  // one singular value
      case Kind::kExact: return b_ < ratio * a_;
    }
    return false;
  }

  /// MayBeBelow and IsBelowRatio of a 2×2 Gram matrix (g11, g22, det G) with the methods'
  /// operations, on any arithmetic type T: a double, or a vector of them lane by lane (a batch's
  /// lanes at once).
  template <typename T, typename Bound>
  static auto GramMayBeBelow(T g11, T g22, T det, Bound bound) -> decltype(det < bound * g11) {
    return det < bound * (g11 + g22);
  }
  template <typename T>
  static auto GramIsBelowRatio(T g11, T g22, T det, double ratio) -> decltype(det < g11) {
    const double q = ratio * ratio;
    const T trace = g11 + g22;
    return det * (1.0 + q) * (1.0 + q) < q * trace * trace;
  }

 private:
  enum class Kind { kExact, kGram1, kGram2 };
  double LargestEigenvalue() const {
    const double half_gap = std::sqrt(0.25 * (a_ - b_) * (a_ - b_) + c_ * c_);
    return 0.5 * (a_ + b_) + half_gap;
  }

  Kind kind_ = Kind::kExact;
  double a_ = 0.0, b_ = 0.0, c_ = 0.0, d_ = 0.0;
};

}  // namespace dpc
