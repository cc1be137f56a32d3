#include "dpc/control/control_law.h"

namespace dpc {

std::string_view ControlStatusName(ControlStatus status) {
  switch (status) {
    case ControlStatus::kOk: return "ok";
    case ControlStatus::kRankDeficient: return "rank-deficient";
    case ControlStatus::kSingular: return "singular";
    case ControlStatus::kNotFinite: return "not-finite";
  }
  return "unknown";
}

}  // namespace dpc
