#include "device_record.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

namespace dpc::services {

struct DeviceRecord::Layout {
  uint64_t magic;
  uint32_t control_count;
  std::atomic<uint32_t> sequence;  ///< odd while a write is under way
  double phi[kMaxControls];
  double rate_per_s[kMaxControls];
  int64_t start_ns;
  int64_t end_ns;
  uint32_t moving;
};

namespace {
constexpr uint64_t kMagic = 0x3130'6472'6f63'6572ULL;  // "recodr01", version 1
}  // namespace

DeviceRecord::DeviceRecord(const std::string& path, int control_count) : path_(path), control_count_(control_count) {
  if (control_count < 1 || control_count > kMaxControls) {
    throw std::runtime_error(fmt::format("device record {}: {} controls", path, control_count));
  }
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (fd < 0) throw std::runtime_error(fmt::format("device record {}: {}", path, std::strerror(errno)));
  struct stat info {};
  const bool ok = ::fstat(fd, &info) == 0 && S_ISREG(info.st_mode) &&
                  (info.st_size == sizeof(Layout) || ::ftruncate(fd, sizeof(Layout)) == 0);
  void* mapping = ok ? ::mmap(nullptr, sizeof(Layout), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0) : MAP_FAILED;
  const int error = errno;
  ::close(fd);
  if (mapping == MAP_FAILED) {
    throw std::runtime_error(fmt::format("device record {}: not a regular file or cannot be mapped ({})", path,
                                         std::strerror(error)));
  }
  layout_ = static_cast<Layout*>(mapping);
}

DeviceRecord::~DeviceRecord() {
  if (layout_ != nullptr) ::munmap(layout_, sizeof(Layout));
}

std::optional<ControlVector> DeviceRecord::LastPhi() const {
  const uint32_t sequence = layout_->sequence.load(std::memory_order_acquire);
  if (layout_->magic != kMagic || static_cast<int>(layout_->control_count) != control_count_ || sequence % 2 != 0 ||
      sequence == 0) {
    return std::nullopt;
  }
  WaveplateMotion motion = WaveplateMotion::Still(ControlVector::Zero(control_count_));
  for (int i = 0; i < control_count_; ++i) {
    motion.phi[i] = layout_->phi[i];
    motion.rate_per_s[i] = layout_->rate_per_s[i];
    if (!std::isfinite(motion.phi[i]) || !std::isfinite(motion.rate_per_s[i])) return std::nullopt;
  }
  motion.start_ns = layout_->start_ns;
  motion.end_ns = layout_->end_ns;
  motion.moving = layout_->moving != 0 && motion.end_ns >= motion.start_ns;
  if (!motion.moving) return motion.phi;
  ControlVector end(control_count_);
  motion.At(motion.end_ns, &end);
  for (int i = 0; i < control_count_; ++i) {
    if (!std::isfinite(end[i])) return std::nullopt;
  }
  return end;
}

void DeviceRecord::Write(const WaveplateMotion& motion) {
  const uint32_t sequence = layout_->sequence.load(std::memory_order_relaxed);
  layout_->sequence.store(sequence | 1u, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  layout_->magic = kMagic;
  layout_->control_count = static_cast<uint32_t>(control_count_);
  const int n = std::min<int>(control_count_, static_cast<int>(motion.phi.size()));
  for (int i = 0; i < n; ++i) {
    layout_->phi[i] = motion.phi[i];
    layout_->rate_per_s[i] = motion.moving ? motion.rate_per_s[i] : 0.0;
  }
  layout_->start_ns = motion.start_ns;
  layout_->end_ns = motion.end_ns;
  layout_->moving = motion.moving ? 1u : 0u;
  layout_->sequence.store((sequence | 1u) + 1u, std::memory_order_release);
}

std::string DeviceRecord::DefaultPath(int domain, const std::string& bench_id, const std::string& driver_id) {
  return fmt::format("/dev/shm/dpc-waveplates-{}-{}-{}", domain, bench_id, driver_id);
}

}  // namespace dpc::services
