#pragma once
/// @file incidence.h
/// Angle of incidence of each beam of a planar scan, from the surface the
/// neighbouring returns trace: the input the intensity calibration needs
/// besides range.
///
/// Returns are first split into surfaces with the adaptive breakpoint rule
/// (Borges & Aldon 2004): consecutive returns belong to the same surface when
/// their distance is at most r·sin Δφ / sin(λ − Δφ) + 3σ, the gap a line seen
/// at the grazing limit λ leaves, so range jumps (an edge in front of a wall)
/// never mix. Each return's normal is the normal of a total-least-squares line
/// through its surface neighbours within a small window; where that window
/// spans a corner (the points do not lie on one line within the range noise)
/// the one-sided window, left or right, that does is used instead.

#include <vector>

#include "slam2d/laser_scan.h"

namespace rmap::slam2d {

struct IncidenceOptions {
  /// Half-width of the line-fit window around a return, metres; widened to
  /// 2.5 beam spacings at long range so a far wall keeps a few neighbours.
  /// The normal's error falls with the window's length (σ/L): on the
  /// simulated building 0.2 m / 8 returns gave 1.35° median error, 0.3 m /
  /// 24 returns 0.5°; corners are handled by the one-sided fallback.
  double window_m = 0.3;
  /// At most this many returns on each side enter the fit.
  int max_neighbours = 24;
  /// Grazing limit of the breakpoint rule (90° − λ), degrees in (0, 90):
  /// surfaces seen more obliquely split into isolated returns.
  double max_incidence_deg = 80.0;
  /// Range noise of the scanner (1σ), metres, > 0: breakpoint margin and
  /// tolerance of the line fit.
  double range_sigma_m = 0.015;

  /// @throws std::invalid_argument naming the first bad option
  void validate() const;
};

/// Per-beam cosine of the angle between the beam and the surface normal, in
/// [0, 1], estimated from neighbouring returns of the same scan; NaN where no
/// normal can be estimated: no return (non-finite range, outside
/// [range_min_m, range_max_m]; range_max_m ≤ 0 means no upper limit), an
/// isolated return (fewer than two surface neighbours in the window), or
/// neighbours that lie on no line.
/// @throws std::invalid_argument when angles_rad and ranges_m differ in size
///         or an option is out of range
std::vector<float> cosIncidence(const LaserScan& scan, const IncidenceOptions& options = {});

}  // namespace rmap::slam2d
