#include "dpc/disturbance/random_source.h"

namespace dpc {
namespace {

constexpr uint64_t kGoldenGamma = 0x9e3779b97f4a7c15ULL;

}  // namespace

uint64_t SplitMix64Mix(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

uint64_t DeriveEngineSeed(uint64_t seed, uint64_t stream) {
  const uint64_t h = SplitMix64Mix(seed + kGoldenGamma);
  return SplitMix64Mix(h + kGoldenGamma * (stream + 1));
}

RandomSource::RandomSource(uint64_t seed, uint64_t stream)
    : seed_(seed), stream_(stream), engine_(DeriveEngineSeed(seed, stream)) {}

}  // namespace dpc
