#pragma once
// rotating_drum (seed 001 §3.2.2-3.2.3): dynamic angle of repose at 4 rpm and the area method
// (occupied cross-sectional area, eq. 20) at 4, 40, 80, 105 and 116 rpm.
#include <array>

#include "core/lab/lab_test.hpp"

namespace demcal::lab {

/// The drum speeds of the area method (seed 001 §3.2.3), rpm of the seed's 100 mm drum.
inline constexpr std::array<int, 5> kDrumSpeeds = {4, 40, 80, 105, 116};

struct RotatingDrumSettings {
  static constexpr const char* kName = "rotating_drum";
  double particles;
  double fill;            ///< filling degree (bulk volume over drum volume)
  double aspect;          ///< depth W over diameter D (44 / 100 in the seed)
  double froude_scaling;  ///< 1: speeds keep the Froude number of the seed's 100 mm drum
  double speed_scale;     ///< multiplies every drum speed
  double angle_time;      ///< (s) at 4 rpm (after the bed has turned to its angle)
  double area_time;       ///< (s) per speed of the area method
  double time_step_safety;

  static std::array<contact::ParamInfo<RotatingDrumSettings>, 8> table() {
    return {
        {{"particles", "-", 20, 1e7, 400, "number of particles", &RotatingDrumSettings::particles},
         {"fill", "-", 0.05, 0.9, 0.43, "filling degree (seed 001: 43 %)",
          &RotatingDrumSettings::fill},
         {"aspect", "-", 0.05, 10, 0.44, "drum depth over diameter (seed 001: 44 / 100 mm)",
          &RotatingDrumSettings::aspect},
         {"froude_scaling", "-", 0, 1, 1,
          "1: scale the seed's rpm to keep the Froude number w^2 D / 2g of its 100 mm drum; "
          "0: use the rpm as they are",
          &RotatingDrumSettings::froude_scaling},
         {"speed_scale", "-", 0.01, 100, 1, "multiplies every drum speed",
          &RotatingDrumSettings::speed_scale},
         {"angle_time", "s", 0.05, 100, 1.5,
          "time at 4 rpm for the dynamic angle, after the bed has turned to its angle",
          &RotatingDrumSettings::angle_time},
         {"area_time", "s", 0.02, 100, 0.8, "time per speed of the area method",
          &RotatingDrumSettings::area_time},
         {"time_step_safety", "-", 0.01, 1.0, 0.2, "time step as a fraction of the critical one",
          &RotatingDrumSettings::time_step_safety}}};
  }
  void finalize(const std::string&) {}
};

LabTestInfo rotating_drum_info();  ///< in catalog.cpp
LabOutput run_rotating_drum(const MaterialModel& material, const Settings& settings,
                            const RunOptions& options);

/// The drum cross-section as an image (seed 001 §3.2.2: ImageJ on photographs): particles of
/// `world` projected along the drum axis z onto a raster of pixel `pixel` over [-R, R]^2.
struct DrumImage {
  int n = 0;  ///< pixels per side
  double pixel = 0.0, radius = 0.0;
  std::vector<char> black;
  bool at(int i, int j) const { return black[static_cast<std::size_t>(j) * n + i] != 0; }
  /// Occupied cross-sectional area in % of the drum's (seed 001 eq. 20).
  double occupied_percent() const;
  /// Angle (deg) of a straight line fitted to the free surface (the top black pixel of each
  /// column) over the middle half of the surface's horizontal extent; gravity along -y.
  double surface_angle() const;
};
DrumImage project_drum(const std::vector<Vec3>& x, const std::vector<double>& radius,
                       double drum_radius, double pixel);

}  // namespace demcal::lab
