#pragma once
// The promises of an accepted target (ValidateTargetConfig), shared by fuzz_read_target and
// fuzz_target_request.
#include <cmath>
#include <stdexcept>

#include "dpc/config/scenario_builders.h"
#include "dpc/config/scenario_validation.h"
#include "fuzz_support.h"

namespace dpc::fuzz {

inline void CheckAcceptedTarget(const TargetConfig& target) {
  DPC_FUZZ_CHECK(target.kind == TargetConfig::Kind::kPoint || target.kind == TargetConfig::Kind::kSet,
                 "out-of-range", "target kind %d", static_cast<int>(target.kind));
  if (target.kind == TargetConfig::Kind::kPoint) {
    const StokesVector& p = target.point;
    DPC_FUZZ_CHECK(AllFiniteVector(p), "non-finite", "accepted point [%g, %g, %g]", p.x(), p.y(), p.z());
    DPC_FUZZ_CHECK(IsUnit(p.x(), p.y(), p.z(), 1e-6), "out-of-range", "accepted point |S| = %.17g", p.norm());
  } else {
    const Vector3& n = target.normal;
    DPC_FUZZ_CHECK(AllFiniteVector(n) && std::isfinite(target.offset), "non-finite",
                   "accepted set [%g, %g, %g]·S = %g", n.x(), n.y(), n.z(), target.offset);
    DPC_FUZZ_CHECK(n.norm() >= kMinAxisLength && std::abs(target.offset) / n.norm() < 1.0, "out-of-range",
                   "accepted set |n| = %g, |c|/|n| = %g", n.norm(), std::abs(target.offset) / n.norm());
  }
  try {
    BuildTarget(target);
  } catch (const std::invalid_argument& e) {
    DPC_FUZZ_CHECK(false, "build", "an accepted target does not build: %s", e.what());
  }
}

}  // namespace dpc::fuzz
