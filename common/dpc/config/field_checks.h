#pragma once
// The field checks that every part of the scenario validation shares (an internal header of the
// config module: include scenario_validation.h from outside it).
//
// Each check throws a ScenarioError located at `path`, the field's path in scenario.proto, with
// a message that says what the value is and what was expected, so that the device, controller
// and scenario checks word their errors alike, e.g. at "controller.step":
//   "-0.1 is not > 0; the task step must be positive (typical 0.01 to 1)".
//
// They live in their own namespace because dpc::RequireUnitStokes (optics/stokes.h, which throws
// std::invalid_argument) would make a two-argument call ambiguous; callers bring in the names
// they use with using-declarations inside their anonymous namespace.

#include <string>
#include <string_view>

#include "dpc/optics/stokes.h"

namespace dpc::field_checks {

/// Relative tolerance on "a whole number of samples" and "at least one sample".
inline constexpr double kSampleCountTolerance = 1e-6;

/// Throws ScenarioError(path, message).
[[noreturn]] void Fail(const std::string& path, std::string message);

/// "[x, y, z]", for messages.
std::string FormatVector(const Vector3& v);

// ---- Scalars. `expected` says what the field should be, e.g. "the task step must be > 0".

void RequireFinite(double value, const std::string& path, std::string_view expected);
/// Finite and > 0.
void RequirePositive(double value, const std::string& path, std::string_view expected);
/// Finite and ≥ 0.
void RequireNonNegative(double value, const std::string& path, std::string_view expected);
/// A finite value at most `max`; `what` names it in the message. Check finiteness first: NaN
/// passes.
void RequireAtMost(double value, double max, const std::string& path, std::string_view what);
/// A rotation rate: finite, ≥ 0, and below π rad per sample.
void RequireRate(double rate_rad_per_s, double sample_rate_hz, const std::string& path);

// ---- Vectors: a non-finite component is reported at its own path (".s1", ".s2", ".s3").

void RequireFiniteVector(const Vector3& v, const std::string& path, std::string_view expected);
/// Finite with |axis| ≥ kMinAxisLength (scenario_validation.h).
void RequireAxis(const Vector3& axis, const std::string& path);
/// Finite with | |S| − 1 | ≤ kUnitNormTolerance.
void RequireUnitStokes(const StokesVector& s, const std::string& path);

}  // namespace dpc::field_checks
