// One rig from one registry (runner/open_rig.hpp, runner/src/backend_registry.cpp and the
// back-ends in runner/src/backends/): the built-in back-ends by name, what a request that
// cannot name a usable device says, and a back-end registered by this test binary.

#include "hapticlab/runner/open_rig.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/status.hpp"
#include "hapticlab/db/database.hpp"
#include "hapticlab/devices/falcon.hpp"
#include "hapticlab/devices/vendor.hpp"
#include "hapticlab/protocols/protocol.hpp"
#include "hapticlab/runner/study_runner.hpp"
#include "hapticlab/test/error_of.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::runner::open_rig_test {
namespace {

using test::ErrorOf;

// A device that stands still.
class ToyDevice final : public devices::HapticDevice {
 public:
  devices::DeviceCapabilities Capabilities() const override { return {.name = "toy"}; }
  devices::ReadResult Read(renderer::DeviceSample*) noexcept override {
    return devices::ReadResult::kNoNewData;
  }
  void WriteForce(const Eigen::Vector3d&) noexcept override {}
  void SetTimeBase(std::chrono::steady_clock::time_point) noexcept override {}
};

TEST(OpenRig, TheRegistryHoldsTheFiveBuiltInBackEnds) {
  const auto names = BackendNames();
  ASSERT_GE(names.size(), 5u);
  EXPECT_EQ(std::vector<std::string>(names.begin(), names.begin() + 5),
            (std::vector<std::string>{"sim", "falcon-twin", "falcon", "dhd", "openhaptics"}));
  EXPECT_EQ(DefaultBackendName(), "sim");
  EXPECT_TRUE(IsSimulatedBackend("sim"));
  EXPECT_TRUE(IsSimulatedBackend("falcon-twin"));
  for (const char* hw : {"falcon", "dhd", "openhaptics", "phantom"})
    EXPECT_FALSE(IsSimulatedBackend(hw)) << hw;
  EXPECT_EQ(SimulatedBackendList(), "sim or falcon-twin");
  EXPECT_TRUE(GetBackend("falcon").needs_firmware);
  EXPECT_EQ(GetBackend("falcon-twin").RigDevice(), "falcon");
  EXPECT_EQ(GetBackend("dhd").RigDevice(), "dhd");
}

TEST(OpenRig, AnUnknownNameListsTheBackEnds) {
  const auto d = ErrorOf([] { (void)GetBackend("phantom"); });
  EXPECT_EQ(d.file, "<command line>");
  EXPECT_EQ(d.field, "device");
  EXPECT_NE(d.message.find("phantom"), std::string::npos) << d.message;
  EXPECT_NE(d.message.find("falcon-twin"), std::string::npos) << d.message;
  EXPECT_EQ(ErrorOf([] { (void)OpenRig({.device = "phantom"}); }).field, "device");
}

TEST(OpenRig, AFalconWithoutFirmwareNamesTheFirmwareField) {
  const auto d = ErrorOf([] { (void)OpenRig({.device = "falcon"}); });
  EXPECT_EQ(d.field, "firmware");
  EXPECT_NE(d.message.find("firmware"), std::string::npos) << d.message;
}

TEST(OpenRig, AVendorBackEndThisBuildLacksIsNamed) {
  if (devices::HaveDhd()) GTEST_SKIP() << "this build has the Force Dimension SDK";
  const auto d = ErrorOf([] { (void)OpenRig({.device = "dhd"}); });
  EXPECT_EQ(d.field, "device");
  EXPECT_NE(d.message.find("SDK"), std::string::npos) << d.message;
}

TEST(OpenRig, TheGenericSimulatedDeviceIsTheEnginesDevice) {
  const auto rig = OpenRig({.device = "sim"});
  ASSERT_NE(rig->sim, nullptr);
  EXPECT_EQ(rig->device, rig->sim->generic.get());
  EXPECT_EQ(rig->sim->twin, nullptr);
  EXPECT_EQ(rig->actuator, &rig->sim->actuator);
  EXPECT_EQ(rig->backend, &GetBackend("sim"));
  EXPECT_EQ(rig->device->Capabilities().name, "sim");
  EXPECT_TRUE(rig->sim->true_device_from_sample[1].isApprox(sim::DefaultSamplePoses()[1]));
  EXPECT_TRUE(rig->device_from_sample[0].isApprox(sim::DefaultSamplePoses()[0]));
  EXPECT_EQ(rig->calibration, DefaultRig("sim").text);
  EXPECT_EQ(rig->description.rfind("sim (generic simulated device, simulated hand); rig built-in "
                                   "(sha256 ",
                                   0),
            0u)
      << rig->description;
  // A simulated rig plays vibration to the hand: a sound card is refused.
  EXPECT_EQ(
      ErrorOf([] { (void)OpenRig({.device = "sim", .actuator = ActuatorKind::kAudio}); }).field,
      "actuator");
}

TEST(OpenRig, TheTwinRunsTheRealFalconBackEndAfterItsFirmwareLoads) {
  RigFile rf = DefaultRig("falcon");
  rf.motor_units_per_Nm = 12000;  // the rig file's calibration reaches the Falcon back-end
  const auto rig = OpenRig({.device = "falcon-twin", .rig_file = rf});
  ASSERT_NE(rig->sim, nullptr);
  EXPECT_FALSE(rig->sim->generic);  // replaced by the twin
  ASSERT_NE(rig->sim->twin, nullptr);
  EXPECT_TRUE(rig->sim->twin->firmware_loaded());
  auto* falcon = dynamic_cast<devices::falcon::FalconDevice*>(rig->device);
  ASSERT_NE(falcon, nullptr);
  EXPECT_EQ(rig->sim->device, rig->device);
  EXPECT_NE(rig->description.find("falcon-twin"), std::string::npos);
  // The samples truly lie where the twin's built-in rig (the Falcon's frame) puts them.
  EXPECT_TRUE(
      rig->sim->true_device_from_sample[0].isApprox(DefaultRig("falcon").DeviceFromSample(0)));
  renderer::DeviceSample s;
  rig->sim->clock.Set(0.001);
  EXPECT_NE(falcon->Read(&s), devices::ReadResult::kLost);
}

TEST(OpenRig, BuiltInRigsFollowTheBackEndsFrame) {
  const RigFile falcon = DefaultRig("falcon"), twin = DefaultRig("falcon-twin");
  const RigFile table = DefaultRig("sim"), unknown = DefaultRig("phantom");
  EXPECT_TRUE(falcon.DeviceFromSample(0).isApprox(twin.DeviceFromSample(0)));
  EXPECT_EQ(twin.device, "falcon-twin");
  EXPECT_NEAR(falcon.DeviceFromSample(0).translation().y(), -0.04, 1e-12);  // below the centre
  EXPECT_TRUE(table.DeviceFromSample(1).isApprox(unknown.DeviceFromSample(1)));
  EXPECT_NEAR(table.DeviceFromSample(1).translation().x(), 0.03, 1e-12);
  // A rig file that names no device describes the default back-end.
  std::string text = RigToToml(falcon);
  const auto at = text.find("device = \"falcon\"\n");
  ASSERT_NE(at, std::string::npos) << text;
  text.erase(at, std::string("device = \"falcon\"\n").size());
  EXPECT_EQ(ParseRig(text, "r.toml").device, "sim");
}

// A back-end registered for one test's scope, so no other test of the binary sees it (a unity
// build runs the tests of several files in one process, in an order of CMake's choosing).
class ScopedBackend {
 public:
  explicit ScopedBackend(RigBackend b) : name_(b.name) { RegisterBackend(std::move(b)); }
  ScopedBackend(const ScopedBackend&) = delete;
  ScopedBackend& operator=(const ScopedBackend&) = delete;
  ~ScopedBackend() { UnregisterBackend(name_); }

 private:
  std::string name_;
};

TEST(OpenRig, ABackEndRegisteredHereOpensByName) {
  static int opened = 0;
  RigBackend b;
  b.name = "toy-open";
  b.help = "a toy";
  b.open = [](const RigRequest& q, const RigFile& rf, Rig* rig) {
    ++opened;
    rig->device = rig->parts.Keep(std::make_unique<ToyDevice>());
    return q.device + " (" + std::to_string(rf.motor_units_per_Nm) + ")";
  };
  const ScopedBackend registered(std::move(b));
  const auto names = BackendNames();
  EXPECT_NE(std::find(names.begin(), names.end(), "toy-open"), names.end());
  const int before = opened;
  const auto rig = OpenRig({.device = "toy-open"});
  EXPECT_EQ(opened, before + 1);
  EXPECT_EQ(rig->device->Capabilities().name, "toy");
  EXPECT_EQ(rig->sim, nullptr);
  EXPECT_EQ(rig->description.rfind("toy-open (10000", 0), 0u) << rig->description;
  // A name is registered once.
  RigBackend again;
  again.name = "toy-open";
  again.open = [](const RigRequest&, const RigFile&, Rig*) { return std::string(); };
  EXPECT_THROW(RegisterBackend(again), PreconditionError);
}

TEST(OpenRig, AScopedRegistrationEndsWithItsScopeAndBuiltInsStay) {
  const auto before = BackendNames();
  {
    RigBackend b;
    b.name = "toy-scoped";
    b.open = [](const RigRequest&, const RigFile&, Rig*) { return std::string(); };
    const ScopedBackend registered(std::move(b));
    EXPECT_NE(FindBackend("toy-scoped"), nullptr);
  }
  EXPECT_EQ(FindBackend("toy-scoped"), nullptr);
  EXPECT_EQ(BackendNames(), before);
  EXPECT_THROW(UnregisterBackend(DefaultBackendName()), PreconditionError);
  EXPECT_NE(FindBackend(DefaultBackendName()), nullptr);
}

// A simulated toy back-end registered here: a whole session runs on it (virtual clock, the
// simulated hand and observer behind the Participant seam) like on the built-in `sim`.
TEST(OpenRig, ASessionRunsOnAToyBackEndRegisteredHere) {
  RigBackend b;
  b.name = "toy-sim";
  b.kind = DeviceKind::kSimulated;
  b.help = "a toy simulated device";
  b.open = [](const RigRequest& q, const RigFile& rf, Rig* rig) {
    auto* s = rig->parts.Keep(std::make_unique<sim::SimRig>(
        q.generic,
        std::array<Eigen::Isometry3d, 2>{rf.DeviceFromSample(0), rf.DeviceFromSample(1)}));
    rig->sim = s;
    rig->device = s->device;
    rig->actuator = &s->actuator;
    return std::string("toy-sim");
  };
  const ScopedBackend registered(std::move(b));
  test::TempDir dir;
  const auto p = protocols::LoadProtocol(test::DataPath("protocols/small.toml"));
  const auto rig = OpenRig({.device = "toy-sim"});
  RunOptions o{.db_path = dir.File("toy.db"), .participant = "P01", .record = RecordMode::kNone};
  o.device = "toy-sim";
  o.rig = rig.get();
  o.stop_after_trials = 8;  // the (unrendered) training trials and a few rated ones
  int sides = 0;
  o.on_side = [&](const SideReport& r) { sides += r.hand_ticks > 0; };
  const auto s = RunStudy(p, o);
  EXPECT_EQ(s.status, db::SessionStatus::kAborted);  // stopped after 8 trials, as asked
  EXPECT_EQ(s.executed, 8);
  EXPECT_GT(sides, 0) << "the simulated hand explored the toy device's sides";
  db::Database d(o.db_path);
  const auto se = d.Sessions(d.Participants(d.Studies()[0].id)[0].id)[0];
  EXPECT_EQ(se.device, "toy-sim");
  int rated = 0;
  for (const auto& t : d.Trials(se.id))
    if (t.status == db::TrialStatus::kCompleted && t.phase != PhaseKind::kTraining) {
      ++rated;
      for (const auto& r : d.Ratings(t.id)) EXPECT_EQ(r.source, db::kRaterSimulated);
    }
  EXPECT_GT(rated, 0);
}

// Device names are written as string literals only in the registry (runner/src/backends/):
// every other file of apps/, runner/, sim/ and devices/ asks the registry. The drivers may
// name themselves (Capabilities().name): the Falcon once in its header, OpenHaptics in its
// glue, the generic simulated device in its model.
TEST(OpenRig, DeviceNamesAreLiteralsOnlyInTheRegistry) {
  namespace fs = std::filesystem;
  const fs::path root = HL_SOURCE_DIR;
  const std::set<std::string> drivers = {"devices/include/hapticlab/devices/falcon.hpp",
                                         "devices/src/openhaptics.cpp",
                                         "sim/include/hapticlab/sim/sim_device.hpp"};
  const std::regex literal(R"re("(sim|falcon-twin|falcon|dhd|openhaptics)")re");
  std::vector<std::string> found;
  int files = 0;
  for (const char* dir : {"apps", "runner", "sim", "devices"})
    for (const auto& e : fs::recursive_directory_iterator(root / dir)) {
      const std::string ext = e.path().extension().string();
      if (!e.is_regular_file() || (ext != ".cpp" && ext != ".hpp")) continue;
      const std::string rel = e.path().lexically_relative(root).generic_string();
      if (rel.starts_with("runner/src/backends/")) continue;
      ++files;
      std::ifstream in(e.path());
      std::string line;
      for (int n = 1; std::getline(in, line); ++n) {
        const auto comment = line.find("//");  // comments may name devices
        if (comment != std::string::npos) line.resize(comment);
        if (std::regex_search(line, literal) && !drivers.count(rel))
          found.push_back(rel + ":" + std::to_string(n) + ": " + line);
      }
    }
  EXPECT_GT(files, 50) << "the sources were not found under " << root;
  std::ostringstream list;
  for (const auto& f : found) list << f << "\n";
  EXPECT_TRUE(found.empty()) << "device names outside the registry:\n" << list.str();
}

}  // namespace
}  // namespace hapticlab::runner::open_rig_test
