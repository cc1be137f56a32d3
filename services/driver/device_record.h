#pragma once
// Where the simulated waveplates are, kept outside the driver process: a small file mapped in
// memory (by default in /dev/shm), written at every Apply, read when a driver starts. Real
// waveplates stay where they were when their driver dies; with this record the simulated ones
// do too, so a driver restarted after kill -9 starts from the φ the bench last had (its
// "read-back") instead of the scenario's initial φ, and the loop resumes without a jump.
//
// The record: a magic number, the control count, a sequence number (odd while being written:
// a record torn by a kill in the middle of a write is not used) and the motion. A record of
// another shape (another stage count, another version) or with non-finite values is ignored.

#include <cstdint>
#include <optional>
#include <string>

#include "dpc/bench/waveplate_motion.h"

namespace dpc::services {

class DeviceRecord {
 public:
  /// Opens (creating if needed) the record at `path` for `control_count` controls. Throws
  /// std::runtime_error naming the path if it cannot be opened or mapped.
  DeviceRecord(const std::string& path, int control_count);
  ~DeviceRecord();
  DeviceRecord(const DeviceRecord&) = delete;
  DeviceRecord& operator=(const DeviceRecord&) = delete;

  /// Where the waveplates were left (the motion's end, still), if the record holds a complete
  /// motion of this shape.
  std::optional<ControlVector> LastPhi() const;
  /// Records `motion` (no system call: a copy into the mapping).
  void Write(const WaveplateMotion& motion);
  const std::string& path() const { return path_; }

  /// The default place: /dev/shm/dpc-waveplates-<domain>-<bench>-<driver id>.
  static std::string DefaultPath(int domain, const std::string& bench_id, const std::string& driver_id);

 private:
  struct Layout;
  std::string path_;
  int control_count_;
  Layout* layout_ = nullptr;
};

}  // namespace dpc::services
