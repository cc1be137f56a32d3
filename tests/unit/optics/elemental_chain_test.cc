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

// ElementalTask against WaveplateChain::Evaluate: each stage's task row (e2·Ω′_e, −e1·Ω′_e) at
// the tangent basis of S_in, and the task error Eᵀ(MᵀS* − S_in) of the model loop and
// EᵀMᵀ(S* − S_out) of the measured loop; the output against WaveplateChain::Output. The
// general code forms M and the generators, ElementalTask turns the basis: the same quantities
// by other operations, equal to round-off.
template <typename Axes>
void ExpectTaskEqualsEvaluate(const Axes& axes, const std::string& text) {
  constexpr int N = Axes::kStages;
  ASSERT_EQ(static_cast<int>(text.size()), N);
  const double k = 2.5;  // rad per unit; Ω′ carries it
  const WaveplateChain chain = WaveplateChain::FromAxes(text, k);
  const Lanes scales = {k, k, k, N == 4 ? k : 0.0};
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 200; ++trial) {
    ControlVector phi(N);
    for (int e = 0; e < N; ++e) phi[e] = 2.0 * normal(rng);
    const StokesVector s_in = StokesVector(normal(rng), normal(rng), normal(rng)).normalized();
    const StokesVector target = StokesVector(normal(rng), normal(rng), normal(rng)).normalized();
    const StokesVector s_out_measured =
        StokesVector(normal(rng), normal(rng), normal(rng)).normalized();
    ChainPose chain_pose;
    chain.ComputePose(phi, &chain_pose);
    ChainKinematics kinematics;
    chain.Evaluate(chain_pose, s_in, &kinematics, false);
    const ElementalPose<N> pose = PoseOf<N>(chain_pose);
    Vector3 e1, e2;
    TangentBasis(s_in, &e1, &e2);
    for (const bool measured : {false, true}) {
      // What the error looks at, in the output frame.
      const StokesVector seen = measured ? StokesVector(target - s_out_measured) : target;
      const double in0 = measured ? 0.0 : e1.dot(s_in), in1 = measured ? 0.0 : e2.dot(s_in);
      double rows0[N], rows1[N], error0, error1;
      ElementalTask(
          axes, pose.cos, pose.sin, scales, e1, e2, seen[0], seen[1], seen[2], in0, in1,
          [&](auto e, double row0, double row1) { rows0[e] = row0, rows1[e] = row1; }, &error0,
          &error1);
      for (int e = 0; e < N; ++e) {
        const Vector3 generator = kinematics.input_generators.col(e);
        EXPECT_NEAR(rows0[e], e2.dot(generator), 1e-14) << text << " stage " << e;
        EXPECT_NEAR(rows1[e], -e1.dot(generator), 1e-14) << text << " stage " << e;
      }
      const Vector3 back = kinematics.mueller.transpose() * seen;
      const Vector3 error = measured ? back : Vector3(back - s_in);
      EXPECT_NEAR(error0, e1.dot(error), 1e-14) << text << (measured ? " measured" : " model");
      EXPECT_NEAR(error1, e2.dot(error), 1e-14) << text << (measured ? " measured" : " model");
    }
    EXPECT_LT((ElementalOutput(axes, pose, s_in) - chain.Output(chain_pose, s_in)).norm(), 1e-15)
        << text;
  }
}

TEST(ElementalChainTest, ThePapersDevicesAtCompileTimeEqualTheGeneralChain) {
  ExpectTaskEqualsEvaluate(PaperAxes3{}, "131");
  ExpectTaskEqualsEvaluate(PaperAxes4{}, "3131");
}

TEST(ElementalChainTest, AxesAtRunTimeEqualTheGeneralChain) {
  using A = ElementalAxis;
  ExpectTaskEqualsEvaluate(RuntimeStageAxes<3>{{A::kS1, A::kS2, A::kS1}}, "121");
  ExpectTaskEqualsEvaluate(RuntimeStageAxes<3>{{A::kS3, A::kS3, A::kS2}}, "332");
  ExpectTaskEqualsEvaluate(RuntimeStageAxes<4>{{A::kS2, A::kS3, A::kS2, A::kS3}}, "2323");
  ExpectTaskEqualsEvaluate(RuntimeStageAxes<4>{{A::kS1, A::kS3, A::kS1, A::kS3}}, "1313");
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
