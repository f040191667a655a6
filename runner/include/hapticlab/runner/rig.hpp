#pragma once
/// @file The rig file (TOML, docs/hardware.md): where the device and the two samples are, the
/// stylus tip offset and the device's force calibration. Frames:
/// - world: the lab's frame, any fixed frame (by default the device's);
/// - device: the frame the device reports positions in and takes forces in;
/// - sample (left, right): origin on the sample's surface, +z out of the sample, x and y in
///   its plane. The renderer works in it (its base plane is z = 0).
/// The engine maps the device's reported point, moved by the stylus tip offset, into the
/// sample frame before the renderer and maps the renderer's force back into the device frame.

#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

namespace hapticlab::runner {

struct RigFile {
  std::string path;    ///< where it was read from (empty: built in)
  std::string text;    ///< the file's content, as recorded with a session
  std::string sha256;  ///< of `text`
  std::string device;  ///< the back-end it describes (informational; a file without one: the
                       ///< default back-end, runner::DefaultBackendName)
  Eigen::Isometry3d world_from_device = Eigen::Isometry3d::Identity();
  std::array<Eigen::Isometry3d, 2> world_from_sample{Eigen::Isometry3d::Identity(),
                                                     Eigen::Isometry3d::Identity()};
  /// From the point the device reports to the stylus tip, in the device frame [m] (the
  /// devices here are translational: the offset does not turn).
  Eigen::Vector3d tip_offset_m = Eigen::Vector3d::Zero();
  double motor_units_per_Nm = 10000;  ///< Falcon: motor effort per N m (force calibration)
  double max_force_N = 0;             ///< > 0: a lower force limit than the device's

  /// The sample's frame in the device frame, for the tip: p_device_point = this * p_sample.
  /// (The engine uses its inverse, EngineOptions::sample_from_device.)
  Eigen::Isometry3d DeviceFromSample(int side) const;
};

/// Reads a rig file. @throws hapticlab::InputError listing every problem (file, line, key)
RigFile LoadRig(const std::string& path);
RigFile ParseRig(const std::string& text, const std::string& path);
/// The rig file text of `r` (round-trips through ParseRig).
std::string RigToToml(const RigFile& r);
/// A pose from an origin and two axes (x is made orthogonal to z). Precondition: z_axis is
/// not zero and x_axis not zero nor parallel to it (PreconditionError otherwise; ParseRig
/// reports such axes in a rig file as an InputError before calling this).
Eigen::Isometry3d PoseFromAxes(const Eigen::Vector3d& origin, const Eigen::Vector3d& x_axis,
                               const Eigen::Vector3d& z_axis);

/// The built-in rig of back-end `device` (runner/open_rig.hpp): a table (device frame = world,
/// z up, samples flat at x = -+3 cm), or for a back-end in the Falcon's frame (y up, z towards
/// the user) samples 4 cm below the workspace centre at (0, 0, 0.125 m), at x = -+2.5 cm. An
/// unregistered name gets the table.
RigFile DefaultRig(const std::string& device);

/// A sample plane from touches on its surface (points in the device frame, >= 3, not on one
/// line): least-squares plane through the centroid; +z is the normal on the side of
/// `up_hint`; x points from the first touch to the second (projected into the plane); the
/// origin is the centroid projected onto the plane. Residuals are point-to-plane distances.
struct PlaneFit {
  Eigen::Isometry3d device_from_sample = Eigen::Isometry3d::Identity();
  double rms_residual_m = 0, max_residual_m = 0;
};
/// The touches are the user's data: @throws InputError on `source` (the file they came from,
/// or "<command line>"), field "points", for fewer than 3 points or collinear points.
PlaneFit FitSamplePlane(const std::vector<Eigen::Vector3d>& points_device_m,
                        const Eigen::Vector3d& up_hint,
                        const std::string& source = "<command line>");

}  // namespace hapticlab::runner
