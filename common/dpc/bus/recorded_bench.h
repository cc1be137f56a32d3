#pragma once
// A bench session as `dpc record` kept it (an MCAP file of the bench's topics), read back for the
// programs that take a recording as their input: `dpc-polarimeter --input-recording` (the
// recorded S_in drives the simulated bench) and `dpc evaluate` (a controller judged on a
// recorded session). Every message is decoded with its type and checked as the services check
// it (bus::Read*); one that fails is counted and left out, never used.
//
// The samples kept are one bench run: the first one in the file from `from_s` on (a sample whose
// sequence number is not above the previous one starts a new run: it and everything after it
// are left out, and `later_runs` says so), at most `duration_s` of bench time. Memory: ~72 bytes
// per sample and ~(24 + 8·controls) per state.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "dpc/bench/bench_messages.h"
#include "dpc/config/scenario_config.h"

namespace dpc::bus {

struct RecordedSample {
  uint64_t log_time_ns = 0;       ///< when the recorder received it
  uint64_t sequence = 0;
  int64_t time_ns = 0;            ///< bench clock
  StokesVector s_in = StokesVector::UnitX();
  StokesVector s_out = StokesVector::UnitX();
};

struct RecordedState {
  uint64_t log_time_ns = 0;
  uint64_t answers_sample = 0;
  bool holding = false;
  size_t phi_offset = 0;          ///< its φ: RecordedBench::state_phi[phi_offset … + controls)
};

struct RecordedTarget {
  uint64_t log_time_ns = 0;
  BenchTarget target;
};

struct RecordedBenchOptions {
  double from_s = 0.0;             ///< bench time after the file's first sample
  double duration_s = 0.0;         ///< 0: to the end of the run
  bool samples_only = false;       ///< no states, targets or devices (an input SOP is all it needs)
};

struct RecordedBench {
  std::string path;
  bool complete = true;            ///< the file ended properly (else: read up to `problem`)
  std::string problem;
  std::string bench_id;
  std::vector<RecordedSample> samples;  ///< one run, sequence numbers rising
  uint64_t samples_missing = 0;    ///< sequence numbers missing between the samples kept
  bool later_runs = false;         ///< a restarted bench's samples follow (left out)
  std::optional<DeviceDescription> device;  ///< the first description
  int controls = 0;                ///< the device's controls (else the first state's)
  std::vector<RecordedState> states;        ///< log-time order, `controls` values each
  std::vector<double> state_phi;
  std::vector<RecordedTarget> targets;      ///< log-time order
  /// Metadata records by name (the last of a name).
  std::map<std::string, std::map<std::string, std::string>> metadata;
  uint64_t rejected = 0;           ///< messages that did not decode or failed their check
  std::string last_rejection;

  /// The sample rate: the median interval of consecutive samples (bench clock); 0 with fewer
  /// than two samples.
  double SampleRateHz() const;
  /// The input SOPs, one per sample of the run in sequence order, a missing sample's filled
  /// with the one before it (so the index stays the bench's sample count).
  RecordedInput Input() const;
};

/// Reads `path`. Throws std::runtime_error if it is not an MCAP file or cannot be read at all;
/// a file cut short is read up to its cut (complete = false).
RecordedBench ReadRecordedBench(const std::string& path, const RecordedBenchOptions& options = {});

}  // namespace dpc::bus
