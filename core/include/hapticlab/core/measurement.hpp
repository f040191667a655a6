#pragma once
/// @file Measurement CSV v1 (DESIGN.md §5): recorded tool kinematics, forces and (optionally)
/// acceleration, in SI units, z the surface normal with the surface at z = 0.
///
///   # hapticlab-measurement v1
///   # material: NAME
///   # key: value            (free metadata: speed_mps, force_N, rate_hz, ...)
///   t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,fx_N,fy_N,fz_N[,acc_mps2][,recording]
///
/// The optional `recording` column (an integer >= 0) says which recording a row came from when
/// several are concatenated into one file: analyses that look for change over time compare
/// rows within a recording, not across recordings.
///
/// or, vibration only (the readers that accept it say so):
///
///   t_s,acc_mps2
///
/// Forces are those the surface exerts on the tool. Rows are in time order.

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

namespace hapticlab {

struct MeasurementRow {
  double t_s = 0;
  Eigen::Vector3d p_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d f_N = Eigen::Vector3d::Zero();
  double acc_mps2 = 0;  ///< normal acceleration at the tool; 0 when the file has none
};

struct Measurement {
  std::string file;
  std::string material;
  std::map<std::string, std::string> metadata;
  bool has_forces = true;
  bool has_acceleration = false;
  /// false for a vibration-only file (t_s and acc_mps2, no positions): see
  /// MeasurementReadOptions::allow_vibration_only.
  bool has_kinematics = true;
  std::vector<MeasurementRow> rows;
  std::vector<int> row_lines;  ///< 1-based source line of each row (for messages)
  /// The `recording` column, one id per row; empty when the file has none (one recording).
  std::vector<int> recording_ids;
};

/// Options for reading a measurement.
struct MeasurementReadOptions {
  /// Only t_s and positions are required; velocities missing -> central differences,
  /// forces missing -> zeros with has_forces = false.
  bool kinematics_only = false;
  /// A file with t_s and acc_mps2 and none of x_m, y_m, z_m is read as vibration only
  /// (has_kinematics = has_forces = false; positions, velocities and forces zero). Without
  /// this option such a file is refused for its missing x_m column.
  bool allow_vibration_only = false;
};

/// Reads a measurement CSV v1. Throws InputError naming file, line and column for missing
/// columns, non-numbers, NaN, and times that do not increase.
Measurement ReadMeasurementCsv(const std::string& path, const MeasurementReadOptions& o = {});
Measurement ParseMeasurementCsv(const std::string& text, const std::string& name,
                                const MeasurementReadOptions& o = {});
/// Writes a measurement CSV v1 (17 significant digits).
void WriteMeasurementCsv(const std::string& path, const Measurement& m);

}  // namespace hapticlab
