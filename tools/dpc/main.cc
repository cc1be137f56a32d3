// dpc: the command-line tool of the Jacobian DPC project.
//
//   dpc sim   [SCENARIO] [flags]   one closed-loop simulation (summary, JSON, trace, figure)
//   dpc sweep [SCENARIO] [flags]   a grid of simulations over rates, methods and seeds, on all cores
//   dpc plot  TRACE -o PNG         the paper-style figure from a trace
//   dpc info  FILE.mcap            what a recording holds (topics, counts, duration, rates, gaps)
//   dpc record -o FILE.mcap        a bench's topics into an MCAP file
//   dpc replay FILE.mcap           a recording re-published with its timing
//   dpc evaluate FILE.mcap --controller CMD   controllers judged on a recorded session
//   dpc calibrate SCENARIO -o OUT    a real EPC's control maps measured with the real polarimeter
//   dpc topic list|echo|hz         the bench's DDS topics (discovery, samples, rates)
//   dpc target --point S1 S2 S3    change a running bench's target (or --set-normal, --linear)
//   dpc monitor                    a running bench's live status on one line
//   dpc dashboard                  a running bench's live view in a web browser

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "dpc/cli/command_line.h"
#include "dpc/cli/exit_code.h"
#include "dashboard_command.h"
#include "calibrate_command.h"
#include "evaluate_command.h"
#include "info_command.h"
#include "monitor_command.h"
#include "plot_command.h"
#include "record_command.h"
#include "replay_command.h"
#include "sim_command.h"
#include "sweep_command.h"
#include "target_command.h"
#include "topic_command.h"

int main(int argc, char** argv) {
  using namespace dpc::tools;
  using dpc::cli::ExitCode;
  using dpc::cli::ToInt;
  CLI::App app{
      "dpc: Jacobian-based dynamic polarization control (Wang et al.), simulator and tools"};
  app.require_subcommand(1);
  SimOptions sim_options;
  CLI::App* sim = AddSimCommand(app, &sim_options);
  SweepOptions sweep_options;
  CLI::App* sweep = AddSweepCommand(app, &sweep_options);
  PlotOptions plot_options;
  CLI::App* plot = AddPlotCommand(app, &plot_options);
  InfoOptions info_options;
  CLI::App* info = AddInfoCommand(app, &info_options);
  RecordOptions record_options;
  CLI::App* record = AddRecordCommand(app, &record_options);
  ReplayOptions replay_options;
  CLI::App* replay = AddReplayCommand(app, &replay_options);
  EvaluateOptions evaluate_options;
  CLI::App* evaluate = AddEvaluateCommand(app, &evaluate_options);
  CalibrateOptions calibrate_options;
  CLI::App* calibrate = AddCalibrateCommand(app, &calibrate_options);
  TopicOptions topic_options;
  CLI::App* topic = AddTopicCommand(app, &topic_options);
  TargetOptions target_options;
  CLI::App* target = AddTargetCommand(app, &target_options);
  MonitorOptions monitor_options;
  CLI::App* monitor = AddMonitorCommand(app, &monitor_options);
  DashboardOptions dashboard_options;
  CLI::App* dashboard = AddDashboardCommand(app, &dashboard_options);
  app.name("dpc");
  dpc::cli::AddVersionFlag(app, "dpc");
  // An unknown command or option is named before CLI11 parses (it would blame something else).
  if (const std::string problem = dpc::cli::UnknownNameProblem(app, dpc::cli::Arguments(argc, argv));
      !problem.empty()) {
    fmt::print(stderr, "{}\nRun with --help for more information.\n", problem);
    return ToInt(ExitCode::kInvalidInput);
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return ToInt(app.exit(e) == 0 ? ExitCode::kOk : ExitCode::kInvalidInput);
  }
  if (*sim) return ToInt(RunSimCommand(sim_options));
  if (*sweep) return ToInt(RunSweepCommand(sweep_options));
  if (*plot) return ToInt(RunPlotCommand(plot_options));
  if (*info) return ToInt(RunInfoCommand(info_options));
  if (*record) return ToInt(RunRecordCommand(record_options));
  if (*replay) return ToInt(RunReplayCommand(replay_options));
  if (*evaluate) return ToInt(RunEvaluateCommand(evaluate_options));
  if (*calibrate) return ToInt(RunCalibrateCommand(calibrate_options));
  if (*topic) return ToInt(RunTopicCommand(topic_options));
  if (*target) return ToInt(RunTargetCommand(target_options));
  if (*monitor) return ToInt(RunMonitorCommand(monitor_options));
  if (*dashboard) return ToInt(RunDashboardCommand(dashboard_options));
  return ToInt(ExitCode::kInvalidInput);
}
