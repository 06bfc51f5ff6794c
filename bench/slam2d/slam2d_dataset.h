#pragma once
/// @file slam2d_dataset.h
/// Inputs of `rmap-bench slam2d`: a CARMEN log or a simulated run, split into
/// what the SLAM may see (scans, stamps, odometry) and what only scoring may
/// see (reference poses, relations, simulated truth).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "datasets/slam_relations.h"
#include "slam2d/laser_scan.h"
#include "slam2d/pose2.h"

namespace rmap::bench {

/// Where the odometry given to the SLAM comes from.
/// - kAuto: a log whose ODOM lines restart at every scan (a corrected log)
///   gives the increments derived from them (odometryFromOdomIncrements);
///   a log with ODOM lines that run on (a raw log) gives its logged robot
///   poses, which are then raw odometry; a log without ODOM lines cannot
///   tell raw from corrected poses and gives none.
/// - kLogged: the robot poses of the scan lines (raw logs only: in a
///   corrected log they are the reference).
/// - kOdomIncrements, kNone: as named.
enum class OdometrySource { kAuto, kLogged, kOdomIncrements, kNone };

struct Slam2dSimOptions {
  std::string laser = "sick";  ///< sick | hokuyo (sim::Laser2dModel presets)
  int poses = 600;             ///< path poses planned through the building (0.1 m apart)
  uint64_t seed = 1;
};

/// What the SLAM sees: one scan and the odometry at its stamp.
struct Slam2dInput {
  slam2d::LaserScan scan;
  std::optional<slam2d::Pose2> odometry;  ///< robot base pose in the odometry frame
};

/// A simulated beam return with its ground truth, for the reflectivity figures.
struct SimReturn {
  uint32_t scan = 0;        ///< index into inputs
  uint32_t beam = 0;
  float true_reflectivity = 0.0f;
};

struct Slam2dDataset {
  std::string name;
  std::vector<Slam2dInput> inputs;
  /// Reference sensor (laser) poses, one per input: the log's logged laser
  /// poses (corrected or raw odometry, see reference_kind), those of a
  /// reference log at the same stamps (absent for stamps it lacks), or the
  /// simulated truth.
  std::vector<std::optional<slam2d::Pose2>> reference;
  std::string reference_kind;  ///< e.g. "corrected poses of the log", "raw odometry of the log", "simulation truth"
  std::string odometry_kind;   ///< what inputs[].odometry holds
  std::vector<datasets::SlamRelation> relations;  ///< empty when none
  size_t relations_dropped = 0;  ///< placed by scan period past the log's last scan (see Slam2dSourceOptions)
  bool simulated = false;
  std::vector<SimReturn> sim_returns;  ///< simulated runs only: every return that hit a surface
  /// Seconds the data spans (scan stamps, max − min), absent when the stamps
  /// do not measure time (all equal, or a gap of over 10 min between
  /// consecutive sorted stamps, as in logs whose stamps were rounded or garbled).
  std::optional<double> duration_s;
  size_t skipped_lines = 0;  ///< log lines of other messages
  size_t stamps_replaced = 0;  ///< scans that took their stamp from Slam2dSourceOptions::stamps_path
  /// The log's stamps did not tell its scans apart (fewer distinct stamps than
  /// half the scans: some corrected logs print them with 6 significant digits,
  /// or as 0), so each scan carries its index as stamp (ns): closures and
  /// revisits still name their scans and can be judged. The numbers measure
  /// no time; duration_s is what the log's own stamps say.
  bool scans_numbered = false;
};

struct Slam2dSourceOptions {
  std::string relations_path;  ///< Kümmerle relation file for scoring, or empty
  /// A CARMEN log whose scan (laser) poses are the reference for the scans
  /// of the source with the same stamps, e.g. a corrected subset of a raw
  /// log; empty: the source's own logged poses.
  std::string reference_path;
  /// A CARMEN log holding the same scans (same ranges to the millimetre)
  /// with the stamps the relations use: each scan found there once takes its
  /// stamp. Corrected logs keep only some scans of a raw log and rewrote
  /// their stamps; this finds them in the raw log. Empty: none.
  std::string stamps_path;
  /// Relations of a log whose stamps were rewritten cannot be placed by stamp
  /// (raw mit-killian: its scans are stamped 0.9 s apart, the relations' scans
  /// 0.44 s). With a period > 0 they are placed by counting instead: the
  /// relations' distinct stamps, sorted, are numbered by their gaps rounded to
  /// whole periods, the first at scan relations_first_scan, and each stamp
  /// becomes its scan's. This holds only where the log kept every scan of the
  /// relations' run, in order; BENCHMARKS.md §4 shows how mit-killian's first
  /// scan was found. 0: by stamp.
  double relations_scan_period_s = 0.0;
  size_t relations_first_scan = 0;
  OdometrySource odometry = OdometrySource::kAuto;
  Slam2dSimOptions sim;
};

/// Places relations on scans by counting scan periods (see
/// Slam2dSourceOptions::relations_scan_period_s); relations that would fall
/// past the last scan are dropped.
/// @param period_s    seconds between the scans of the relations' run
/// @param first_scan  index into `inputs` of the relations' earliest stamp
/// @return relations dropped
/// @throws std::invalid_argument for a period that is not positive and finite,
///         or a gap between two distinct relation stamps that is not within
///         0.3 of a whole number (≥ 1) of periods: the period is wrong there
size_t placeRelationsByScanPeriod(std::vector<datasets::SlamRelation>& relations,
                                  const std::vector<Slam2dInput>& inputs, double period_s, size_t first_scan);

/// Loads SOURCE: a CARMEN log (plain, .gz, .bz2) or `sim:building` (a
/// procedural one-storey building of clients/sim, a 2D laser preset driven
/// along a planned tour, truth known; the robot turns on the spot at corners,
/// ≤ 5° per scan, and its odometry is the true motion with 1 % scale bias and
/// random errors).
/// @throws std::runtime_error naming the file when it cannot be read, for an
///         odometry source the log cannot give, or for a reference log that
///         shares no stamp with the source
Slam2dDataset loadSlam2dDataset(const std::string& source, const Slam2dSourceOptions& options);

/// Parses "auto", "logged", "odom-increments", "none".
/// @throws std::invalid_argument otherwise
OdometrySource parseOdometrySource(const std::string& name);

}  // namespace rmap::bench
