#include "dpc/optics/elemental_chain.h"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <type_traits>

#include "dpc/optics/waveplate_chain.h"

namespace dpc {
namespace {

// The pose of φ for WaveplateChain::FromAxes(axes, k) as an ElementalPose.
template <int N>
ElementalPose<N> PoseOf(const ChainPose& chain_pose) {
  ElementalPose<N> pose;
  for (int e = 0; e < N; ++e) {
    pose.phi[e] = chain_pose.phi[e];
    pose.cos[e] = chain_pose.cos[e];
    pose.sin[e] = chain_pose.sin[e];
  }
  return pose;
}

// The forward pass against WaveplateChain::Evaluate: M, and each stage's axis in the input frame
// (Ω′_e / k) dotted with a vector; the output against WaveplateChain::Output. The same
// operations, but GCC 12 may pair a rotation's two rows into one fused multiply-add-subtract in
// either (its vectorizer does so despite -ffp-contract=off), hence a last-bit tolerance.
template <typename Axes>
void ExpectForwardPassEqualsEvaluate(const Axes& axes, const std::string& text) {
  constexpr int N = Axes::kStages;
  ASSERT_EQ(static_cast<int>(text.size()), N);
  const double k = 1.0;  // Ω′ is then the input-frame axis itself
  const WaveplateChain chain = WaveplateChain::FromAxes(text, k);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 200; ++trial) {
    ControlVector phi(N);
    for (int e = 0; e < N; ++e) phi[e] = 2.0 * normal(rng);
    const StokesVector s_in = StokesVector(normal(rng), normal(rng), normal(rng)).normalized();
    const Vector3 w(normal(rng), normal(rng), normal(rng));
    ChainPose chain_pose;
    chain.ComputePose(phi, &chain_pose);
    ChainKinematics kinematics;
    chain.Evaluate(chain_pose, s_in, &kinematics, false);
    const ElementalPose<N> pose = PoseOf<N>(chain_pose);
    double m[3][3];
    double dots[N];
    ElementalForwardPass(axes, pose.cos, pose.sin, m, [&](auto e, const auto& axis) {
      dots[e] = axis.Dot(w[0], w[1], w[2]);
    });
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(m[r][c], kinematics.mueller(r, c), 1e-15) << text;
    }
    for (int e = 0; e < N; ++e) {
      // The general code scales first (Ω′ = k·row); with k = 1 the products are the row's.
      const Vector3 generator = kinematics.input_generators.col(e);
      EXPECT_NEAR(dots[e], generator.dot(w), 1e-15 * (1.0 + w.norm())) << text << " stage " << e;
    }
    EXPECT_LT((ElementalOutput(axes, pose, s_in) - chain.Output(chain_pose, s_in)).norm(), 1e-15)
        << text;
  }
}

TEST(ElementalChainTest, ThePapersDevicesAtCompileTimeEqualTheGeneralChain) {
  ExpectForwardPassEqualsEvaluate(PaperAxes3{}, "131");
  ExpectForwardPassEqualsEvaluate(PaperAxes4{}, "3131");
}

TEST(ElementalChainTest, AxesAtRunTimeEqualTheGeneralChain) {
  using A = ElementalAxis;
  ExpectForwardPassEqualsEvaluate(RuntimeStageAxes<3>{{A::kS1, A::kS2, A::kS1}}, "121");
  ExpectForwardPassEqualsEvaluate(RuntimeStageAxes<3>{{A::kS3, A::kS3, A::kS2}}, "332");
  ExpectForwardPassEqualsEvaluate(RuntimeStageAxes<4>{{A::kS2, A::kS3, A::kS2, A::kS3}}, "2323");
  ExpectForwardPassEqualsEvaluate(RuntimeStageAxes<4>{{A::kS1, A::kS3, A::kS1, A::kS3}}, "1313");
}

TEST(ElementalChainTest, ThePapersDevicesAreDispatchedToTheirCompileTimeAxes) {
  using A = ElementalAxis;
  const auto fixed = [](std::initializer_list<A> axes) {
    return DispatchStageAxes(axes.begin(), static_cast<int>(axes.size()), [](const auto& a) {
      return std::decay_t<decltype(a)>::kFixed;
    });
  };
  EXPECT_TRUE(fixed({A::kS1, A::kS3, A::kS1}));
  EXPECT_TRUE(fixed({A::kS3, A::kS1, A::kS3, A::kS1}));
  EXPECT_FALSE(fixed({A::kS3, A::kS1, A::kS3}));
  EXPECT_FALSE(fixed({A::kS1, A::kS3, A::kS1, A::kS3}));
  const A axes[] = {A::kS2, A::kS3, A::kS1};
  const int second = DispatchStageAxes(axes, 3, [](const auto& a) { return static_cast<int>(a.At(1)); });
  EXPECT_EQ(second, static_cast<int>(A::kS3));
}

TEST(ElementalChainTest, AnIdleLaneIsAControlAtZero) {
  const ElementalPose<3> pose;
  EXPECT_EQ(pose.phi[3], 0.0);
  EXPECT_EQ(pose.cos[3], 1.0);
  EXPECT_EQ(pose.sin[3], 0.0);
}

}  // namespace
}  // namespace dpc
