#include "dpc/optics/numeric_jacobian.h"

#include <fmt/format.h>

#include <stdexcept>

namespace dpc {

Matrix3X NumericJacobian(const WaveplateChain& chain, const ControlVector& phi,
                         const StokesVector& s_in, double step) {
  const int n = chain.control_count();
  if (phi.size() != n) {
    throw std::invalid_argument(
        fmt::format("NumericJacobian: {} control values for a chain with {} controls",
                    phi.size(), n));
  }
  if (!(step > 0.0)) {
    throw std::invalid_argument(fmt::format("NumericJacobian: step {} must be > 0", step));
  }
  Matrix3X jacobian(3, n);
  ControlVector shifted = phi;
  for (int c = 0; c < n; ++c) {
    shifted[c] = phi[c] + step;
    const StokesVector plus = chain.Output(shifted, s_in);
    shifted[c] = phi[c] - step;
    const StokesVector minus = chain.Output(shifted, s_in);
    shifted[c] = phi[c];
    jacobian.col(c) = (plus - minus) / (2.0 * step);
  }
  return jacobian;
}

}  // namespace dpc
