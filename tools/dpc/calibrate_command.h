#pragma once
// `dpc calibrate SCENARIO -o CALIBRATED.pbtxt`: the control maps of a real EPC measured with the
// real polarimeter (the scenario's waveplate_device and polarimeter_device; the bench's services
// stopped). Each stage's channel is swept through its range while the others stay at the
// reference voltage; at each voltage the chain's whole rotation is fitted from simultaneous
// input and output SOPs taken while the input moves (the polarimeter must measure both:
// reply S_IN_AND_S_OUT); the stage's retardance follows from the rotation relative to the
// reference (calibration.h), the absolute offsets from a least-squares fit of the model chain to
// every measured rotation. Each stage's map becomes a monotonic lookup table of retardance
// against volts (from a least-squares polynomial through the measurements); the fit's residuals
// are reported, and the scenario with the tables is written for the driver and the controllers.

#include <CLI/CLI.hpp>

#include <string>

#include "dpc/cli/exit_code.h"

namespace dpc::tools {

struct CalibrateOptions {
  std::string scenario_path;
  std::string output_path;
  int points = 41;               ///< voltages per stage, over its range
  int readings = 12;             ///< SOP pairs per voltage
  double dwell_s = 0.12;         ///< the readings are spread over this long (the input moves)
  double settle_s = 0.02;        ///< after setting a voltage, before reading
  double reference_v = 0.0;      ///< the other channels' voltage (clamped into each range)
  int degree = 5;                ///< of the polynomial the table is taken from
  bool json = false;
};

CLI::App* AddCalibrateCommand(CLI::App& app, CalibrateOptions* options);
cli::ExitCode RunCalibrateCommand(const CalibrateOptions& options);

}  // namespace dpc::tools
