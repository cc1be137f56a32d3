// What every entry point says about itself and about a command line it cannot take: --version
// names the project's and Fast DDS's versions (dpc, the three services and the emulator); an unknown
// subcommand or option is named, with the nearest known one, and exits 2.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "support/command_line_fixture.h"

namespace {

using dpc::testing::Result;

class EntryPointsTest : public dpc::testing::CommandLineTest {
 protected:
  Result RunBinary(const std::string& binary, std::vector<std::string> args) {
    args.insert(args.begin(), binary);
    return dpc::testing::Run(std::move(args), dir_, "run" + std::to_string(++runs_), std::chrono::seconds(30));
  }
  void ExpectRefused(const Result& r, const std::string& message) {
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
  }
};

TEST_F(EntryPointsTest, VersionNamesTheProjectAndFastDdsEverywhere) {
  const std::vector<std::pair<std::string, std::string>> binaries = {{DPC_BINARY, "dpc"},
                                                                     {DPC_DRIVER_BINARY, "dpc-driver"},
                                                                     {DPC_CONTROLLER_BINARY, "dpc-controller"},
                                                                     {DPC_POLARIMETER_BINARY, "dpc-polarimeter"},
                                                                     {DPC_EMULATOR_BINARY, "dpc-emulator"}};
  for (const auto& [binary, name] : binaries) {
    const Result r = RunBinary(binary, {"--version"});
    EXPECT_EQ(r.exit_code, 0) << name << ": " << r.err;
    EXPECT_EQ(r.out.rfind(name + " 0.", 0), 0u) << r.out;
    EXPECT_NE(r.out.find("Fast DDS 2."), std::string::npos) << r.out;
  }
}

TEST_F(EntryPointsTest, AnUnknownSubcommandIsNamedWithTheNearestOne) {
  ExpectRefused(Dpc("simm"), "dpc: unknown command 'simm' (did you mean sim?); the commands are sim, sweep,");
  ExpectRefused(Dpc("topic eco"), "dpc topic: unknown command 'eco' (did you mean echo?)");
  ExpectRefused(Dpc("frobnicate"), "dpc: unknown command 'frobnicate'; the commands are");
}

TEST_F(EntryPointsTest, AnUnknownOptionIsNamedNotTakenForAScenarioFile) {
  // Before: "scenario: File does not exist: gp" (the flag's value taken for the positional).
  const Result sim = Dpc("sim --metod gp");
  ExpectRefused(sim, "dpc sim: unknown option --metod (did you mean --method?)");
  EXPECT_EQ(sim.err.find("File does not exist"), std::string::npos) << sim.err;
  ExpectRefused(Dpc("sweep --seeds=3 --rates-rad-per-sec 1e4"), "dpc sweep: unknown option --rates-rad-per-sec");
  ExpectRefused(RunBinary(DPC_CONTROLLER_BINARY, {"--prioity", "3"}),
                "dpc-controller: unknown option --prioity (did you mean --priority?)");
  ExpectRefused(RunBinary(DPC_DRIVER_BINARY, {"--max-slew", "3", "x.pbtxt"}), "dpc-driver: unknown option --max-slew");
  ExpectRefused(RunBinary(DPC_EMULATOR_BINARY, {"--dac-bit", "12"}),
                "dpc-emulator: unknown option --dac-bit (did you mean --dac-bits?)");
}

TEST_F(EntryPointsTest, ServicesRunUnderARealTimePriorityOrSayWhyNot) {
  ExpectRefused(RunBinary(DPC_POLARIMETER_BINARY, {"--realtime-priority", "100"}), "--realtime-priority");
  const Result r = RunBinary(DPC_POLARIMETER_BINARY,
                             {"--realtime-priority", "3", "--run-s", "0.3", "--rate-hz", "500", "--domain", "178"});
  if (r.exit_code == 0) {
    EXPECT_NE(r.err.find("real-time priority 3 (SCHED_FIFO)"), std::string::npos) << r.err;
  } else {  // a machine without CAP_SYS_NICE: refused at start, saying what it needs
    EXPECT_EQ(r.exit_code, 4) << r.err;
    EXPECT_NE(r.err.find("CAP_SYS_NICE"), std::string::npos) << r.err;
  }
}

TEST_F(EntryPointsTest, KnownOptionsValuesAndHelpStillParse) {
  EXPECT_EQ(Dpc("sim --help").exit_code, 0);
  EXPECT_EQ(Dpc("topic echo --help").exit_code, 0);
  const Result r = Dpc("sim --method=gp --duration-s 3e-3 --rate-rad-per-s 1e4");  // "--name=value" too
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

}  // namespace
