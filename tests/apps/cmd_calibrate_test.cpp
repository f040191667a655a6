// hapticlab study calibrate through the command line (apps/hapticlab/cmd_calibrate.cpp): a tiny
// calibration (the small test protocol, 2 pool participants, 2 simulated studies per
// evaluation, 2 sweeps) whose printed loss is the weighted squared miss of its printed table,
// whose search never worsens the loss, and whose observer file lands next to the targets file
// and loads in a protocol. (The shipped calibration against the dissertation's tables:
// CalibratedObserver in tests/design/calibration_test.cpp.)

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::cmd_calibrate_test {
namespace {

namespace fs = std::filesystem;

std::string Cli() { return HL_CLI_PATH; }

// The targets file: two targets with different weights, two free parameters.
std::string Targets(const std::string& target_protocol) {
  return "[fit]\nseed = 5\nsimulations = 2\npool = 2\nsweeps = 2\nobserver = \"o.toml\"\n\n"
         "[[protocol]]\nid = \"small\"\nfile = \"small.toml\"\nparticipants = 4\n\n"
         "[[param]]\nname = \"upper\"\nlo = 60\nhi = 95\nstep = 4\n\n"
         "[[param]]\nname = \"range_sd\"\nlo = 0\nhi = 1\nstep = 0.1\n\n"
         "[[target]]\nprotocol = \"" +
         target_protocol +
         "\"\nstatistic = \"sd\"\ncriterion = \"roughness\"\nvalue = 20\nweight = 1\n\n"
         "[[target]]\nprotocol = \"small\"\nstatistic = \"sd\"\ncriterion = \"overall\"\n"
         "value = 15\nweight = 0.5\n";
}

TEST(CalibrateCli, TheLossIsTheWeightedMissOfTheTableAndTheObserverLoads) {
  test::TempDir dir;
  fs::create_directory(dir.File("t"));
  for (const char* f : {"small.toml", "profiles.toml"})
    fs::copy_file(test::DataPath(std::string("protocols/") + f), dir.File(std::string("t/") + f));
  test::WriteFile(dir.File("t/cal.toml"), Targets("small"));
  std::string out;
  // Run from another folder: the observer is written next to the targets file.
  ASSERT_EQ(test::RunCommand("{ cd " + dir.path() + " && " + Cli() +
                                 " study calibrate t/cal.toml 2> " + dir.File("log.txt") + "; }",
                             &out),
            0)
      << out << test::ReadFile(dir.File("log.txt"));
  ASSERT_TRUE(fs::exists(dir.File("t/o.toml"))) << out;
  // The table: | protocol | statistic | target | weight | achieved |, then "loss L; ...".
  std::istringstream in(out);
  std::string line;
  double sum = 0, loss = -1;
  int rows = 0;
  while (std::getline(in, line)) {
    char proto[64], stat[64], crit[64];
    double target = 0, weight = 0, achieved = 0;
    if (std::sscanf(line.c_str(), "| %63s | %63s %63s | %lf | %lf | %lf |", proto, stat, crit,
                    &target, &weight, &achieved) == 6) {
      sum += weight * (achieved - target) * (achieved - target);
      ++rows;
    }
    std::sscanf(line.c_str(), "loss %lf;", &loss);
  }
  ASSERT_EQ(rows, 2) << out;
  ASSERT_GE(loss, 0) << out;
  EXPECT_NEAR(loss, sum, 2e-3 * sum + 1e-3) << out;  // the table's values have 3 decimals
  // The search keeps only improvements: the logged losses never rise.
  std::istringstream log(test::ReadFile(dir.File("log.txt")));
  std::vector<double> losses;
  while (std::getline(log, line)) {
    double l = 0;
    int k = 0;
    if (std::sscanf(line.c_str(), "start: loss %lf", &l) == 1 ||
        std::sscanf(line.c_str(), "sweep %d: loss %lf", &k, &l) == 2)
      losses.push_back(l);
  }
  ASSERT_EQ(losses.size(), 3u) << test::ReadFile(dir.File("log.txt"));
  for (std::size_t i = 1; i < losses.size(); ++i) EXPECT_LE(losses[i], losses[i - 1]);
  EXPECT_NEAR(losses.back(), loss, 1e-4 + 1e-4 * loss);
  // The observer file is one a protocol can name.
  std::string proto = test::ReadFile(dir.File("t/small.toml"));
  proto.replace(proto.find("seed = 42"), 9, "seed = 42\nobserver = \"o.toml\"");
  test::WriteFile(dir.File("t/with_observer.toml"), proto);
  EXPECT_EQ(test::RunCommand(Cli() + " study validate " + dir.File("t/with_observer.toml"), &out),
            0)
      << out;
}

TEST(CalibrateCli, ATargetOfAnUnknownProtocolIsNamedWithFileAndLine) {
  test::TempDir dir;
  test::WriteFile(dir.File("cal.toml"), Targets("ch9"));
  std::string out;
  EXPECT_EQ(test::RunCommand(Cli() + " study calibrate " + dir.File("cal.toml") + " --quiet", &out),
            2);
  EXPECT_NE(out.find(dir.File("cal.toml") + ":"), std::string::npos) << out;
  EXPECT_NE(out.find("ch9"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir.File("o.toml")));
}

}  // namespace
}  // namespace hapticlab::cmd_calibrate_test
