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
//
// With --temperatures-c or --wavelengths-nm the whole calibration is repeated at each condition
// (a shell command, or the person at the terminal, brings the device there first), and each
// stage's map becomes tables keyed by the condition with an operating point: the driver and the
// controllers use the table interpolated there (ResolveConditionTables, scenario_builders.h).

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

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
  /// Calibrate at each of these (2 to 16; one of the two lists): the maps become tables keyed
  /// by temperature or wavelength, resolved at the operating point (ResolveConditionTables).
  std::vector<double> temperatures_c, wavelengths_nm;
  std::string condition_command;           ///< brings the device to {value}; empty: ask at the terminal
  double condition_settle_s = 0.0;         ///< after a condition is reached
  std::optional<double> operating_point;   ///< °C or nm; default the first condition
  bool json = false;
};

CLI::App* AddCalibrateCommand(CLI::App& app, CalibrateOptions* options);
cli::ExitCode RunCalibrateCommand(const CalibrateOptions& options);

}  // namespace dpc::tools
