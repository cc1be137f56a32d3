#include "dpc/optics/count_dispatch.h"

#include <gtest/gtest.h>

#include <array>
#include <string>
#include <type_traits>

namespace dpc {
namespace {

// The compile-time value DispatchCount passed, as seen by the callee.
int FixedValueFor(int n) {
  return DispatchCount(n, [](auto fixed) { return decltype(fixed)::value; });
}

TEST(CountDispatchTest, ThreeAndFourAreFixedAtCompileTime) {
  EXPECT_EQ(FixedValueFor(3), 3);
  EXPECT_EQ(FixedValueFor(4), 4);
}

TEST(CountDispatchTest, OtherCountsGetZero) {
  for (int n : {-1, 0, 1, 2, 5, 16, 1000}) EXPECT_EQ(FixedValueFor(n), 0) << n;
}

// The exact type the callee receives for `n`, compared with std::integral_constant<int, kExpected>.
template <int kExpected>
bool ReceivesIntegralConstant(int n) {
  return DispatchCount(n, [](auto fixed) {
    return std::is_same_v<decltype(fixed), std::integral_constant<int, kExpected>>;
  });
}

TEST(CountDispatchTest, TheArgumentIsExactlyAnIntegralConstant) {
  EXPECT_TRUE(ReceivesIntegralConstant<3>(3));
  EXPECT_TRUE(ReceivesIntegralConstant<4>(4));
  EXPECT_TRUE(ReceivesIntegralConstant<0>(2));
  EXPECT_TRUE(ReceivesIntegralConstant<0>(5));
  EXPECT_FALSE(ReceivesIntegralConstant<3>(4));
  // Its value is a constant expression (e.g. usable as a fixed Eigen size).
  DispatchCount(4, [](auto fixed) {
    constexpr int kValue = decltype(fixed)::value;
    static_assert(kValue == 0 || kValue == 3 || kValue == 4);
  });
}

TEST(CountDispatchTest, FixedOrPrefersTheCompileTimeCount) {
  static_assert(FixedOr(std::integral_constant<int, 3>{}, 7) == 3);
  static_assert(FixedOr(std::integral_constant<int, 4>{}, 7) == 4);
  static_assert(FixedOr(std::integral_constant<int, 0>{}, 7) == 7);
  EXPECT_EQ(FixedOr(std::integral_constant<int, 0>{}, 11), 11);
  EXPECT_EQ(FixedOr(std::integral_constant<int, 3>{}, 11), 3);
}

TEST(CountDispatchTest, TheDocumentedPatternLoopsExactlyNTimes) {
  for (int n : {1, 2, 3, 4, 5, 9}) {
    int iterations = 0;
    DispatchCount(n, [&](auto fixed) {
      const int count = FixedOr(fixed, n);
      for (int i = 0; i < count; ++i) ++iterations;
    });
    EXPECT_EQ(iterations, n) << n;
  }
}

TEST(CountDispatchTest, ReturnValuesAreForwarded) {
  EXPECT_EQ(DispatchCount(4, [](auto fixed) { return FixedOr(fixed, 0) * 10; }), 40);
  const std::string text =
      DispatchCount(6, [](auto fixed) { return "fixed " + std::to_string(fixed.value); });
  EXPECT_EQ(text, "fixed 0");
  const double value = DispatchCount(3, [](auto) { return 2.5; });
  EXPECT_DOUBLE_EQ(value, 2.5);
}

TEST(CountDispatchTest, ReferencesAreForwardedAsReferences) {
  int storage = 1;
  // decltype(auto): a callee returning int& gives the caller int&, not a copy.
  int& ref = DispatchCount(5, [&](auto) -> int& { return storage; });
  ref = 42;
  EXPECT_EQ(storage, 42);
  static_assert(std::is_same_v<decltype(DispatchCount(3, [&](auto) -> int& { return storage; })),
                               int&>);
}

TEST(CountDispatchTest, ForEachIndexVisitsEachIndexInOrderAsAConstant) {
  std::array<int, 4> seen{};
  int calls = 0;
  ForEachIndex<4>([&](auto i) {
    static_assert(std::is_same_v<decltype(i), std::integral_constant<int, decltype(i)::value>>);
    std::array<int, decltype(i)::value + 1> sized{};  // a constant expression
    seen[calls++] = static_cast<int>(sized.size()) - 1;
  });
  EXPECT_EQ(calls, 4);
  EXPECT_EQ(seen, (std::array<int, 4>{0, 1, 2, 3}));
  ForEachIndex<0>([&](auto) { ++calls; });
  EXPECT_EQ(calls, 4);
}

}  // namespace
}  // namespace dpc
