#include "hapticlab/devices/falcon.hpp"

#include <fmt/format.h>
#include <libusb-1.0/libusb.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <stdexcept>

#include "hapticlab/core/status.hpp"

namespace hapticlab::devices::falcon {
namespace {

constexpr double kPi = std::numbers::pi;

// Stamper's delta geometry of the Falcon (libnifalcon's published constants, here in metres).
constexpr double kA = 0.060, kB = 0.1025, kC = 0.014, kD = 0.01125, kE = 0.01125, kF = -0.025;
constexpr double kS = -0.027330909, kR = 0.037233758;
constexpr double kPhi[3] = {kPi / 2, -kPi / 6, -5 * kPi / 6};

}  // namespace

// ---------------------------------------------------------------------------------------------
std::array<std::uint8_t, 16> EncodeCommand(const Command& c) {
  std::array<std::uint8_t, 16> p{};
  p[0] = '<';
  p[15] = '>';
  for (std::size_t m = 0; m < 3; ++m) {
    const auto v = static_cast<std::uint16_t>(c.motor[m]);
    for (std::size_t k = 0; k < 4; ++k)
      p[1 + 4 * m + k] = static_cast<std::uint8_t>((v >> (4 * k)) & 0xf);
  }
  p[13] = static_cast<std::uint8_t>((c.leds & 0x0e) | (c.homing ? 0x01 : 0x00));
  p[14] = 0;
  for (int i = 1; i < 15; ++i)
    p[static_cast<std::size_t>(i)] =
        static_cast<std::uint8_t>(p[static_cast<std::size_t>(i)] + 0x41);
  return p;
}

bool DecodeStatus(const std::uint8_t* d, std::size_t n, Status* out, int* malformed) {
  bool found = false;
  std::size_t at = 0;
  while (at < n) {
    if (d[at] != '<') {
      ++at;
      continue;
    }
    if (at + 16 > n) break;
    bool ok = d[at + 15] == '>';
    // Data nibbles are 'A'..'P'; byte 13 carries homing bits above the nibble.
    for (std::size_t i = 1; ok && i < 13; ++i) ok = d[at + i] >= 0x41 && d[at + i] <= 0x50;
    ok = ok && d[at + 13] >= 0x41;
    if (!ok) {
      if (malformed) ++*malformed;
      ++at;
      continue;
    }
    for (std::size_t m = 0; m < 3; ++m) {
      std::uint16_t v = 0;
      for (std::size_t k = 0; k < 4; ++k)
        v = static_cast<std::uint16_t>(v | ((d[at + 1 + 4 * m + k] - 0x41) & 0xf) << (4 * k));
      out->encoder[m] = static_cast<std::int16_t>(v);
    }
    const int info = d[at + 13] - 0x41;
    out->buttons = static_cast<std::uint8_t>(info & 0x0f);
    out->homing = static_cast<std::uint8_t>((info >> 4) & 0x07);
    found = true;
    at += 16;
  }
  return found;
}

// ---------------------------------------------------------------------------------------------
double EncoderToAngle(std::int16_t count) {
  // Arc length of the shaft per count over the drum's circumference, in degrees, plus the offset.
  const double deg = (14.25 * kPi / (320.0 * 4.0)) * count / (kPi * 110.0 / 360.0) + 35.0;
  return deg * kPi / 180.0;
}

bool InverseKinematics(const Eigen::Vector3d& p, Eigen::Vector3d* theta) {
  for (int arm = 0; arm < 3; ++arm) {
    const double cp = std::cos(kPhi[arm]), sp = std::sin(kPhi[arm]);
    const double pu = -kR + cp * p.x() + sp * p.y();
    const double pv = -kS + cp * p.y() - sp * p.x();
    const double pw = p.z();
    const double c3 = (pv + kF) / kB;
    if (!(std::abs(c3) <= 1)) return false;
    const double th3 = std::acos(c3), s3 = std::sin(th3);
    const double common = pw * pw + pu * pu + 2 * kC * pu + kA * kA + kC * kC - kD * kD - kE * kE -
                          kB * kB * s3 * s3 - 2 * kB * kE * s3 - 2 * kB * kD * s3 - 2 * kD * kE;
    const double l0 = common - 2 * kA * pu - 2 * kA * kC;
    const double l1 = -4 * kA * pw;
    const double l2 = common + 2 * kA * pu + 2 * kA * kC;
    const double disc = l1 * l1 - 4 * l2 * l0;
    if (!(disc >= 0) || l2 == 0) return false;
    const double t = -(std::sqrt(disc) + l1) / (2 * l2);
    (*theta)[arm] = 2 * std::atan(t);
  }
  return theta->allFinite();
}

namespace {
bool Jacobian(const Eigen::Vector3d& p, Eigen::Matrix3d* J) {  // d(theta)/d(p)
  const double h = 1e-7;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d a = p, b = p, ta, tb;
    a[k] += h;
    b[k] -= h;
    if (!InverseKinematics(a, &ta) || !InverseKinematics(b, &tb)) return false;
    J->col(k) = (ta - tb) / (2 * h);
  }
  return J->allFinite();
}
}  // namespace

bool ForwardKinematics(const Eigen::Vector3d& theta, const Eigen::Vector3d& guess,
                       Eigen::Vector3d* p) {
  Eigen::Vector3d x = guess;
  for (int it = 0; it < 20; ++it) {
    Eigen::Vector3d th;
    Eigen::Matrix3d J;
    if (!InverseKinematics(x, &th) || !Jacobian(x, &J)) return false;
    const Eigen::Vector3d r = theta - th;
    if (r.norm() < 1e-9) {
      *p = x;
      return true;
    }
    Eigen::Vector3d step = J.fullPivLu().solve(r);
    // Damped: halve the step until the residual falls (stays inside the workspace).
    for (int k = 0; k < 20; ++k) {
      Eigen::Vector3d th2;
      if (InverseKinematics(x + step, &th2) && (theta - th2).norm() < r.norm()) break;
      step *= 0.5;
    }
    x += step;
  }
  Eigen::Vector3d th;
  if (InverseKinematics(x, &th) && (theta - th).norm() < 1e-9) {
    *p = x;
    return true;
  }
  return false;
}

bool ForceToTorque(const Eigen::Vector3d& p, const Eigen::Vector3d& f, Eigen::Vector3d* tau) {
  Eigen::Matrix3d J;
  if (!Jacobian(p, &J)) return false;
  // Virtual work: tau . dtheta = f . dp with dp = J^-1 dtheta, so tau = J^-T f.
  *tau = J.transpose().fullPivLu().solve(f);
  return tau->allFinite();
}

// ---------------------------------------------------------------------------------------------
namespace {

class LibusbTransport final : public UsbTransport {
 public:
  explicit LibusbTransport(int index) {
    if (libusb_init(&ctx_) < 0) throw std::runtime_error("libusb: cannot initialise");
    libusb_device** list = nullptr;
    const auto n = libusb_get_device_list(ctx_, &list);
    libusb_device* found = nullptr;
    int seen = 0;
    for (ssize_t i = 0; i < n; ++i) {
      libusb_device_descriptor d{};
      if (libusb_get_device_descriptor(list[i], &d) == 0 && d.idVendor == kVendorId &&
          d.idProduct == kProductId && seen++ == index)
        found = list[i];
    }
    int rc = found ? libusb_open(found, &h_) : LIBUSB_ERROR_NOT_FOUND;
    libusb_free_device_list(list, 1);
    if (rc < 0) {
      libusb_exit(ctx_);
      throw std::runtime_error(
          fmt::format("falcon: no device {} (vendor 0x{:04x}, product 0x{:04x}): {}", index,
                      kVendorId, kProductId, libusb_strerror(rc)));
    }
    libusb_set_auto_detach_kernel_driver(h_, 1);
    if ((rc = libusb_claim_interface(h_, 0)) < 0) {
      libusb_close(h_);
      libusb_exit(ctx_);
      throw std::runtime_error(
          std::string("falcon: cannot claim interface 0 (permissions? docs/hardware.md): ") +
          libusb_strerror(rc));
    }
  }
  ~LibusbTransport() override {
    libusb_release_interface(h_, 0);
    libusb_close(h_);
    libusb_exit(ctx_);
  }
  int Control(std::uint8_t type, std::uint8_t req, std::uint16_t value, std::uint16_t index,
              unsigned timeout_ms) override {
    return libusb_control_transfer(h_, type, req, value, index, nullptr, 0, timeout_ms);
  }
  int BulkWrite(const std::uint8_t* data, int n, unsigned timeout_ms) override {
    int done = 0;
    const int rc = libusb_bulk_transfer(h_, kEndpointOut, const_cast<std::uint8_t*>(data), n, &done,
                                        timeout_ms);
    return rc < 0 ? rc : done;
  }
  int BulkRead(std::uint8_t* data, int n, unsigned timeout_ms) override {
    int done = 0;
    const int rc = libusb_bulk_transfer(h_, kEndpointIn, data, n, &done, timeout_ms);
    return rc < 0 && rc != LIBUSB_ERROR_TIMEOUT ? rc : done;
  }

 private:
  libusb_context* ctx_ = nullptr;
  libusb_device_handle* h_ = nullptr;
};

}  // namespace

std::unique_ptr<UsbTransport> OpenLibusb(int index) {
  return std::make_unique<LibusbTransport>(index);
}

int CountDevices() {
  libusb_context* ctx = nullptr;
  if (libusb_init(&ctx) < 0) return 0;
  libusb_device** list = nullptr;
  const auto n = libusb_get_device_list(ctx, &list);
  int count = 0;
  for (ssize_t i = 0; i < n; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) == 0 && d.idVendor == kVendorId &&
        d.idProduct == kProductId)
      ++count;
  }
  if (n >= 0) libusb_free_device_list(list, 1);
  libusb_exit(ctx);
  return count;
}

// ---------------------------------------------------------------------------------------------
FalconDevice::FalconDevice(std::unique_ptr<UsbTransport> usb, std::function<double()> clock,
                           const FalconOptions& o)
    : usb_(std::move(usb)), clock_(std::move(clock)), o_(o) {
  HL_REQUIRE(usb_ != nullptr, "falcon: a transport is required");
}

DeviceCapabilities FalconDevice::Capabilities() const {
  DeviceCapabilities c;
  c.name = kDeviceName;
  c.max_force_N = o_.max_force_N;
  c.max_stiffness_N_per_m = 2000;  // stable on the Falcon at 1 kHz (order of the vendor's figure)
  c.max_rate_hz = 1000;
  c.workspace_m = {0.10, 0.10, 0.10};
  return c;
}

void FalconDevice::WriteForce(const Eigen::Vector3d& f) noexcept {
  Eigen::Vector3d tau;
  if (!have_p_ || !f.allFinite() || !ForceToTorque(p_m_, f, &tau)) {
    cmd_.motor = {0, 0, 0};
    return;
  }
  for (int m = 0; m < 3; ++m) {
    // Positive torque on the model's joint is a negative command on the Falcon's motors.
    const double u = std::clamp(-tau[m] * o_.motor_units_per_Nm, -32767.0, 32767.0);
    cmd_.motor[static_cast<std::size_t>(m)] = static_cast<std::int16_t>(std::lround(u));
  }
}

ReadResult FalconDevice::Read(DeviceSample* out) noexcept {
  const auto packet = EncodeCommand(cmd_);
  if (usb_->BulkWrite(packet.data(), 16, o_.io_timeout_ms) != 16) {
    ++lost_reads_;
    return ReadResult::kLost;
  }
  const int n = usb_->BulkRead(buf_.data(), static_cast<int>(buf_.size()), o_.io_timeout_ms);
  if (n < 0) {
    ++lost_reads_;
    return ReadResult::kLost;
  }
  // Two FTDI modem-status bytes lead every read; the payload joins what the last read left.
  const std::size_t payload = n > 2 ? static_cast<std::size_t>(n - 2) : 0;
  if (pending_n_ + payload > pending_.size()) {  // keep the newest bytes
    const std::size_t drop = pending_n_ + payload - pending_.size();
    std::memmove(pending_.data(), pending_.data() + drop, pending_n_ - drop);
    pending_n_ -= drop;
  }
  std::memcpy(pending_.data() + pending_n_, buf_.data() + 2, payload);
  pending_n_ += payload;
  Status st;
  const bool found = DecodeStatus(pending_.data(), pending_n_, &st, &malformed_);
  // Keep an incomplete packet at the end ('<' in the last 15 bytes) for the next read.
  std::size_t keep_from = pending_n_;
  for (std::size_t i = pending_n_ > 15 ? pending_n_ - 15 : 0; i < pending_n_; ++i)
    if (pending_[i] == '<') {
      keep_from = i;
      break;
    }
  std::memmove(pending_.data(), pending_.data() + keep_from, pending_n_ - keep_from);
  pending_n_ -= keep_from;
  if (!found) {
    ++empty_reads_;
    return ReadResult::kNoNewData;
  }
  ++packets_;
  status_ = st;
  const Eigen::Vector3d theta(EncoderToAngle(st.encoder[0]), EncoderToAngle(st.encoder[1]),
                              EncoderToAngle(st.encoder[2]));
  Eigen::Vector3d p;
  if (!ForwardKinematics(theta, p_m_, &p)) {
    ++lost_reads_;
    return ReadResult::kLost;
  }
  const double t =
      clock_ ? clock_()
             : std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  p_m_ = p;
  have_p_ = true;
  out->state.p_m = p;
  out->state.v_mps = velocity_.Update(p, t, o_.velocity_cutoff_hz);
  out->t_s = t;
  return ReadResult::kOk;
}

}  // namespace hapticlab::devices::falcon
