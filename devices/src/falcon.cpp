#include "hapticlab/devices/falcon.hpp"

#include <fmt/format.h>
#include <libusb-1.0/libusb.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
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
const char* LoadStateName(LoadState s) {
  switch (s) {
    case LoadState::kIdle:
      return "idle";
    case LoadState::kPurge:
      return "purge";
    case LoadState::kLineSetup:
      return "line set-up";
    case LoadState::kHandshake:
      return "bootloader handshake";
    case LoadState::kBootloader:
      return "bootloader baud switch";
    case LoadState::kUpload:
      return "upload";
    case LoadState::kNormalMode:
      return "normal mode";
    case LoadState::kVerify:
      return "verify";
    case LoadState::kDone:
      return "done";
    case LoadState::kFailed:
      return "failed";
  }
  return "?";
}

namespace {

struct Attempt {
  UsbTransport& usb;
  const LoadOptions& o;
  LoadResult& r;
  LoadState state = LoadState::kIdle;

  bool Fail(const std::string& what) {
    r.failed_in = state;
    r.error = fmt::format("{} (state: {})", what, LoadStateName(state));
    return false;
  }
  void Enter(LoadState s) {
    state = s;
    r.trace.push_back(s);
  }
  bool Ctl(std::uint8_t req, std::uint16_t value, const char* what) {
    const int rc = usb.Control(ftdi::kRequestType, req, value, 0, o.timeout_ms);
    return rc >= 0 || Fail(fmt::format("{}: USB error {}", what, rc));
  }
  bool Write(const std::uint8_t* d, int n, const char* what) {
    const int rc = usb.BulkWrite(d, n, o.timeout_ms);
    return rc == n || Fail(fmt::format("{}: wrote {} of {} bytes", what, rc, n));
  }
  // Reads and strips the two FTDI status bytes; returns payload bytes or -1.
  int Read(std::uint8_t* d, int n) {
    std::uint8_t raw[64 + 2];
    const int rc = usb.BulkRead(raw, std::min(n + 2, 64), o.timeout_ms);
    if (rc < 2) return rc < 0 ? -1 : 0;
    std::memcpy(d, raw + 2, static_cast<std::size_t>(rc - 2));
    return rc - 2;
  }

  bool Run(const std::vector<std::uint8_t>& fw) {
    Enter(LoadState::kPurge);
    if (!Ctl(ftdi::kReset, ftdi::kPurgeRx, "purge rx") ||
        !Ctl(ftdi::kReset, ftdi::kPurgeTx, "purge tx"))
      return false;
    Enter(LoadState::kLineSetup);
    if (!Ctl(ftdi::kLatency, 16, "latency 16 ms") ||
        !Ctl(ftdi::kBaudRate, ftdi::kBaud9600, "9600 baud") || !Ctl(ftdi::kData, 8, "8N1") ||
        !Ctl(ftdi::kFlowCtrl, 0, "no flow control") ||
        !Ctl(ftdi::kModemCtrl, ftdi::kRtsLow, "RTS low") ||
        !Ctl(ftdi::kModemCtrl, ftdi::kDtrLow, "DTR low") ||
        !Ctl(ftdi::kModemCtrl, ftdi::kDtrHigh, "DTR high"))
      return false;
    Enter(LoadState::kHandshake);
    const std::uint8_t hello[3] = {0x0a, 0x43, 0x0d}, answer[4] = {0x0a, 0x44, 0x2c, 0x0d};
    bool greeted = false;
    for (int i = 0; i < o.handshake_tries && !greeted; ++i) {
      if (!Write(hello, 3, "handshake")) return false;
      std::uint8_t in[64];
      const int n = Read(in, 62);
      // Some hosts see a leading 0x00 before the answer.
      if (n == 4 && std::memcmp(in, answer, 4) == 0) greeted = true;
      if (n == 5 && in[0] == 0 && std::memcmp(in + 1, answer, 4) == 0) greeted = true;
    }
    if (!greeted)
      return Fail(fmt::format(
          "no bootloader answer to 0x0a 'C' 0x0d after {} tries (is the Falcon powered?)",
          o.handshake_tries));
    Enter(LoadState::kBootloader);
    if (!Ctl(ftdi::kModemCtrl, ftdi::kDtrLow, "DTR low") ||
        !Ctl(ftdi::kBaudRate, ftdi::kBaud140000, "140000 baud"))
      return false;
    const std::uint8_t a = 'A';
    if (!Write(&a, 1, "bootloader 'A'")) return false;
    std::uint8_t echo[64];
    if (Read(echo, 1) != 1 || echo[0] != 'A') return Fail("bootloader did not echo 'A'");
    Enter(LoadState::kUpload);
    for (std::size_t at = 0; at < fw.size();) {
      const int n = static_cast<int>(std::min<std::size_t>(62, fw.size() - at));
      if (!Write(fw.data() + at, n, "firmware block")) return false;
      int got = 0;
      while (got < n) {
        std::uint8_t in[64];
        const int k = Read(in, n - got);
        if (k <= 0)
          return Fail(fmt::format("no echo for firmware bytes {}-{} (time-out {} ms)",
                                  at + static_cast<std::size_t>(got),
                                  at + static_cast<std::size_t>(n), o.timeout_ms));
        if (std::memcmp(in, fw.data() + at + got, static_cast<std::size_t>(k)) != 0)
          return Fail(fmt::format("echo of firmware bytes from {} differs (line noise?)",
                                  at + static_cast<std::size_t>(got)));
        got += k;
      }
      at += static_cast<std::size_t>(n);
    }
    Enter(LoadState::kNormalMode);
    if (!Ctl(ftdi::kLatency, 1, "latency 1 ms") ||
        !Ctl(ftdi::kBaudRate, ftdi::kBaudNormal, "normal baud") ||
        !Ctl(ftdi::kReset, ftdi::kPurgeRx, "purge rx") ||
        !Ctl(ftdi::kReset, ftdi::kPurgeTx, "purge tx"))
      return false;
    Enter(LoadState::kVerify);
    const auto packet = EncodeCommand({});
    std::uint8_t in[64];
    std::vector<std::uint8_t> stream;
    for (int i = 0; i < o.verify_tries; ++i) {
      if (!Write(packet.data(), 16, "status request")) return false;
      const int k = Read(in, 62);
      if (k > 0) stream.insert(stream.end(), in, in + k);
      Status st;
      if (DecodeStatus(stream.data(), stream.size(), &st)) {
        Enter(LoadState::kDone);
        return true;
      }
    }
    return Fail(
        fmt::format("firmware loaded but no valid status packet in {} exchanges", o.verify_tries));
  }
};

}  // namespace

LoadResult LoadFirmware(UsbTransport& usb, const std::vector<std::uint8_t>& fw,
                        const LoadOptions& o) {
  LoadResult r;
  if (fw.empty()) {
    r.error = "empty firmware";
    r.failed_in = LoadState::kIdle;
    return r;
  }
  for (int a = 1; a <= o.attempts; ++a) {
    r.attempts = a;
    r.trace.clear();
    Attempt at{usb, o, r};
    if (at.Run(fw)) {
      r.ok = true;
      r.error.clear();
      return r;
    }
    r.trace.push_back(LoadState::kFailed);
  }
  r.error = fmt::format("firmware load failed after {} attempts: {}", o.attempts, r.error);
  return r;
}

std::vector<std::uint8_t> ReadFirmwareFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f)
    throw InputError(
        path, 0, "firmware",
        "cannot open the firmware file (supply the Falcon firmware yourself; docs/hardware.md)");
  std::vector<std::uint8_t> d((std::istreambuf_iterator<char>(f)), {});
  if (d.empty()) throw InputError(path, 0, "firmware", "empty firmware file");
  return d;
}

// ---------------------------------------------------------------------------------------------
FalconDevice::FalconDevice(std::unique_ptr<UsbTransport> usb, std::function<double()> clock,
                           const FalconOptions& o)
    : usb_(std::move(usb)), clock_(std::move(clock)), o_(o) {
  HL_REQUIRE(usb_ != nullptr, "falcon: a transport is required");
}

DeviceCapabilities FalconDevice::Capabilities() const {
  DeviceCapabilities c;
  c.name = "falcon";
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
  if (have_p_ && t > t_s_) {
    const double dt = t - t_s_, a = 1 - std::exp(-2 * kPi * o_.velocity_cutoff_hz * dt);
    v_mps_ += a * ((p - p_m_) / dt - v_mps_);
  }
  p_m_ = p;
  t_s_ = t;
  have_p_ = true;
  out->state.p_m = p;
  out->state.v_mps = v_mps_;
  out->t_s = t;
  return ReadResult::kOk;
}

}  // namespace hapticlab::devices::falcon
