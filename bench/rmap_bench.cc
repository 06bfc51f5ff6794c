/// rmap-bench: benchmarks of rmap's engines against their anchors, side by side.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "load/load_bench.h"
#include "loop/loop_bench.h"
#include "loop_sim/loop_sim_bench.h"
#include "map3d/map3d_bench.h"
#include "replay/replay_check.h"
#include "server/server_bench.h"
#include "slam2d/slam2d_bench.h"
#include "slam2d/calibration_eval.h"

int main(int argc, char** argv) {
  CLI::App app{"rmap-bench: rmap against its anchors (OctoMap, ...) in one process; prints ratios, writes JSON"};
  app.require_subcommand(1);

  rmap::bench::Map3dBenchOptions map3d;
  map3d.shared_data_dir = RMAP_SHARED_DATA_DIR;
  CLI::App* m = app.add_subcommand("map3d", "cuboid occupancy map vs OctoMap 1.9");
  m->add_option("--scans", map3d.source,
                "scan.dat-style cloud (.bz2/.gz ok), 3DTK uos folder, sim:geb079 or sim:building")
      ->required();
  m->add_option("--resolution", map3d.resolution_m, "base cell edge, metres")->check(CLI::PositiveNumber);
  m->add_option("--fusion-tolerance", map3d.fusion_tolerance, "log-odds span fused into one cuboid (default: library)")
      ->check(CLI::NonNegativeNumber);
  m->add_option("--fuse-after-scans", map3d.fuse_after_scans, "fuse blocks untouched for this many scans")
      ->check(CLI::NonNegativeNumber);
  m->add_option("--threads", map3d.threads, "threads for both maps")->check(CLI::Range(1, 64));
  m->add_option("--max-range", map3d.max_range_m, "metres; rays beyond are truncated (default unlimited)");
  m->add_option("--sensor-model", map3d.sensor_models, "beam, endpoint or both")
      ->check(CLI::IsMember({"beam", "endpoint", "both"}));
  m->add_option("--free-space", map3d.free_space,
                "ray walks: exact (OctoMap's cells), stop-at-freed, or auto (exact when --fusion-tolerance is 0)")
      ->check(CLI::IsMember({"auto", "exact", "stop-at-freed"}));
  m->add_option("--json", map3d.json_out, "write results as JSON to this file");
  m->add_option("--shared-data", map3d.shared_data_dir, "folder of the shared datasets (for sim:geb079)");
  m->add_option("--sim-poses", map3d.sim.poses, "simulated trajectory length")->check(CLI::Range(1, 100000));
  m->add_option("--sim-rings", map3d.sim.rings, "simulated lidar rings")->check(CLI::Range(1, 1024));
  m->add_option("--sim-columns", map3d.sim.columns, "simulated lidar columns")->check(CLI::Range(1, 16384));
  m->add_option("--sim-seed", map3d.sim.seed, "simulation seed");
  m->add_option("--sim-sensor-height", map3d.sim.sensor_height_m, "simulated lidar height above the floor, metres")
      ->check(CLI::PositiveNumber);

  rmap::bench::ServerBenchOptions server;
  CLI::App* s = app.add_subcommand("server", "rmapd over loopback: simulated robots streaming, HTTP queries");
  s->add_option("--robots", server.robots, "simulated robots streaming at once")->check(CLI::Range(1, 1024));
  s->add_flag("--shared-map", server.shared_map, "all robots on one map (default: one map each)");
  s->add_option("--resolution", server.resolution_m, "map resolution, metres")->check(CLI::PositiveNumber);
  s->add_option("--phase-seconds", server.phase_s, "length of each timed phase")->check(CLI::PositiveNumber);
  s->add_option("--lidar-rings", server.lidar_rings, "simulated lidar rings")->check(CLI::Range(1, 1024));
  s->add_option("--lidar-columns", server.lidar_columns, "simulated lidar columns")->check(CLI::Range(1, 16384));
  s->add_option("--query-connections", server.query_connections, "keep-alive connections for point queries")
      ->check(CLI::Range(1, 256));
  s->add_option("--batch-points", server.batch_points, "points per batch query")->check(CLI::Range(1, 10000000));
  s->add_option("--insert-threads", server.insert_threads, "threads tracing one cloud")->check(CLI::Range(1, 64));
  s->add_option("--json", server.json_out, "write results as JSON to this file");

  rmap::bench::LoadBenchOptions load;
  CLI::App* lo = app.add_subcommand("load", "a running rmapd under many robots, viewers (some stalled) and queries at once");
  lo->add_option("--server", load.server_url, "http://HOST:PORT of the rmapd under load");
  lo->add_option("--token", load.token, "admin bearer token (none in loopback-only mode)");
  lo->add_option("--robots", load.robots, "robots streaming at once")->check(CLI::Range(1, 1024));
  lo->add_option("--laser-robots", load.laser_robots, "of them, 2D-laser robots (the rest: 3D lidar)")
      ->check(CLI::Range(0, 1024));
  lo->add_flag("--shared-map", load.shared_map, "all robots on one map (default: one map each)");
  lo->add_option("--rate", load.rate_hz, "messages per second per robot")->check(CLI::PositiveNumber);
  lo->add_option("--seconds", load.seconds, "length of the run")->check(CLI::PositiveNumber);
  lo->add_option("--lidar-rings", load.lidar_rings, "simulated lidar rings")->check(CLI::Range(1, 1024));
  lo->add_option("--lidar-columns", load.lidar_columns, "simulated lidar columns")->check(CLI::Range(1, 16384));
  lo->add_option("--viewers", load.viewers, "viewer streams of every map")->check(CLI::Range(0, 4096));
  lo->add_option("--stalled-viewers", load.stalled_viewers, "of them, viewers that never read")
      ->check(CLI::Range(0, 4096));
  lo->add_option("--query-connections", load.query_connections, "keep-alive connections querying back to back")
      ->check(CLI::Range(1, 256));
  lo->add_option("--json", load.json_out, "write results as JSON to this file");

  rmap::bench::Slam2dBenchOptions slam2d;
  CLI::App* d = app.add_subcommand("slam2d", "2D laser SLAM on a CARMEN log or a simulated run: relation error, ATE, RPE, speed");
  d->add_option("--log", slam2d.source, "CARMEN log (.gz/.bz2 ok) or sim:building")->required();
  d->add_option("--relations", slam2d.relations_path, "Kümmerle et al. relation file (t1 t2 x y z roll pitch yaw)");
  d->add_option("--reference", slam2d.reference_path,
                "CARMEN log whose scan poses at the same stamps are the reference for ATE/RPE (default: the log's own)");
  d->add_option("--stamps-from", slam2d.stamps_path,
                "CARMEN log holding the same scans with the stamps the relations use (a corrected log's raw log)");
  CLI::Option* period = d->add_option("--relations-period", slam2d.relations_scan_period_s,
                                      "seconds between the relations' scans: place the relations by counting scans "
                                      "instead of by stamp (a log whose stamps were rewritten)")
                            ->check(CLI::PositiveNumber);
  d->add_option("--relations-first-scan", slam2d.relations_first_scan,
                "with --relations-period: 0-based index of the scan at the relations' earliest stamp")
      ->needs(period);
  d->add_option("--json", slam2d.json_out, "write results as JSON to this file");
  d->add_option("--poses", slam2d.poses_out, "write the estimated laser poses (stamp_s x y theta) to this file");
  d->add_option("--revisits", slam2d.revisits_out,
                "write each revisit's residual (earlier_stamp_s later_stamp_s earlier_scan later_scan points run_m "
                "[reference_m]; scans are 0-based indices into the log) to this file");
  d->add_option("--odometry", slam2d.odometry,
                "odometry given to the SLAM: auto (raw log: logged poses; corrected log: ODOM increments; "
                "no ODOM lines: none), logged, odom-increments, none")
      ->check(CLI::IsMember({"auto", "logged", "odom-increments", "none"}));
  d->add_flag_callback("--no-odometry", [&] { slam2d.odometry = "none"; }, "same as --odometry none");
  d->add_option("--max-scans", slam2d.max_scans, "only the first N scans (0: all)");
  d->add_option("--repeat", slam2d.repeat,
                "runs of the log: the first as it is, the others from seeded other starts (rigid moves); "
                "JSON `repeated` gives each run and the median ATE")
      ->check(CLI::Range(1, 1000));
  d->add_option("--start", slam2d.start,
                "X_M Y_M THETA_RAD: the run moved to this start, as --repeat moves its runs (one of them in full)")
      ->expected(3);
  d->add_option("--rpe-distance", slam2d.rpe_distance_m, "travel of the RPE pairs, metres")->check(CLI::PositiveNumber);
  d->add_option("--sim-laser", slam2d.sim.laser, "simulated 2D laser preset")->check(CLI::IsMember({"sick", "hokuyo"}));
  d->add_option("--sim-poses", slam2d.sim.poses, "simulated path poses (0.1 m apart)")->check(CLI::Range(2, 1000000));
  d->add_option("--sim-seed", slam2d.sim.seed, "simulation seed (building and noise)");
  d->add_option("--resolution", slam2d.slam.resolution_m, "finest cell edge, metres")->check(CLI::PositiveNumber);
  d->add_option("--levels", slam2d.slam.levels, "map pyramid levels")->check(CLI::Range(1, 8));
  d->add_option("--map-update-distance", slam2d.slam.map_update_distance_m, "metres moved between map updates");
  d->add_option("--map-update-angle", slam2d.slam.map_update_angle_rad, "radians turned between map updates");
  d->add_option("--range-max", slam2d.slam.range_max_m, "beams beyond are ignored, metres")->check(CLI::PositiveNumber);
  d->add_option("--odometry-information-xy", slam2d.slam.odometry_information_xy, "odometry prior weight, 1/m^2");
  d->add_option("--odometry-information-theta", slam2d.slam.odometry_information_theta, "odometry prior weight, 1/rad^2");
  d->add_option("--odometry-heading-kappa", slam2d.slam.odometry_heading_kappa,
                "sparse trajectories: heading prior kappa / sigma^2 from the odometry's heading agreement (0: off)");
  d->add_option("--max-odometry-information-theta", slam2d.slam.max_odometry_information_theta,
                "cap of that heading prior, 1/rad^2");
  d->add_option("--odometry-translation-kappa", slam2d.slam.odometry_translation_kappa,
                "sparse trajectories: translation prior kappa / sigma^2 from the odometry's step agreement (0: off)");
  d->add_option("--max-odometry-information-xy", slam2d.slam.max_odometry_information_xy,
                "cap of that translation prior, 1/m^2");
  d->add_option("--reflectivity-weight", slam2d.slam.reflectivity_weight, "weight of the reflectivity residual");
  d->add_option("--match-point-spacing", slam2d.slam.match_point_spacing_m, "spacing of the matched endpoints, metres");
  d->add_option("--coarse-iterations", slam2d.slam.matcher.coarse_iterations, "Gauss-Newton iterations per coarse level");
  d->add_option("--fine-iterations", slam2d.slam.matcher.fine_iterations, "Gauss-Newton iterations on the finest level");
  d->add_option("--flat-information-cells", slam2d.slam.matcher.flat_information_cells,
                "dense trajectories: odometry prior along a level's nearly flat direction, 1/cell^2 (0: off)");
  d->add_option("--flat-ratio", slam2d.slam.matcher.flat_ratio,
                "eigenvalue ratio below which a level's translation direction counts as flat");
  d->add_option("--matcher-damping", slam2d.slam.matcher.damping, "Levenberg damping of the scan matcher, relative to the Hessian trace");
  d->add_option("--value-floor", slam2d.slam.occupancy.value_floor_probability,
                "occupancy probability the scan matcher reads as empty (0: it reads the probability itself)");
  d->add_option("--sparse-search-without-odometry-rad", slam2d.slam.sparse_search_without_odometry_rad,
                "heading half-width (rad) of a sparse trajectory's search without odometry");
  d->add_option("--search-rotation-weight", slam2d.slam.search_without_odometry_rotation_weight,
                "without odometry, a searched pose's score is weighed by exp(-w·Δθ²) (1/rad²)");
  d->add_option("--search-after-step-heading-weight", slam2d.slam.search_after_large_step_heading_weight,
                "the search after a large odometry step weighs a pose's score by exp(-w·I·Δθ²), I the heading prior's information");
  d->add_option("--search-after-step-m", slam2d.slam.search_after_large_step_m,
                "half-width (m) of the translation search after a large odometry step");
  d->add_option("--search-after-step-translation-weight", slam2d.slam.search_after_large_step_translation_weight,
                "the search after a large odometry step weighs a pose's score by exp(-w·|Δt|²) (1/m²)");
  d->add_option("--search-translation-weight", slam2d.slam.search_without_odometry_translation_weight,
                "without odometry, a searched pose's score is weighed by exp(-w·|Δt|²) (1/m²)");
  d->add_option("--relock-margin", slam2d.slam.relock_residual_margin, "match residual above the recent mean that triggers a search (<= 0: off)");
  d->add_option("--relock-after-step-m", slam2d.slam.relock_after_large_step_m,
                "half-width (m) of the unweighted search that re-locks a poor fit after a large odometry step (0: off)");
  std::string loop_closure = "off";  // off by default: the front-end figures stay comparable
  d->add_option("--loop-closure", loop_closure, "loop closure with a pose graph (scored: the corrected trajectory)")
      ->check(CLI::IsMember({"on", "off"}));
  d->add_option("--map-image", slam2d.map_image_out, "write the final occupancy map as an 8-bit PGM to this file");
  d->add_option("--map-image-max-px", slam2d.map_image_max_px, "scale the map image down to this longer side")
      ->check(CLI::PositiveNumber);
  d->add_option("--closure-reference", slam2d.closure_reference_paths,
                "corrected CARMEN log of the same run whose poses judge the closures (scans found by their ranges); "
                "repeat for several judges, the first gives the headline figures");
  d->add_option("--submap-keyframes", slam2d.slam.loop_closure.submap_keyframes, "keyframes per loop-closure submap");
  d->add_option("--rerender-shift-m", slam2d.slam.loop_closure.rerender_shift_m,
                "a correction moving a keyframe this far (m) re-renders the map");
  d->add_option("--rerender-shift-rad", slam2d.slam.loop_closure.rerender_shift_rad,
                "a correction turning a keyframe this much (rad) re-renders the map");
  d->add_option("--rerender-checkpoints", slam2d.slam.loop_closure.rerender_checkpoints,
                "map copies kept along the keyframes, where a re-rendering after a correction starts (0: from the first keyframe)")
      ->check(CLI::NonNegativeNumber);
  d->add_option("--local-map-keyframes", slam2d.slam.local_map_keyframes,
                "a sparse trajectory's scans are matched against its newest keyframes only (this many at most; 0: the whole map)");
  d->add_option("--sparse-scan-motion", slam2d.slam.sparse_scan_motion_m,
                "mean motion between scans (m) from which a trajectory counts as sparse");
  d->add_option("--sparse-raster-dilation", slam2d.slam.loop_closure.sparse_raster_dilation_cells,
                "max filter radius (cells) of a sparse submap's loop-closure raster");
  d->add_option("--sparse-min-score", slam2d.slam.loop_closure.sparse_min_score,
                "correlative score a loop closure against a sparse submap needs");
  d->add_option("--sparse-loop-edges", slam2d.slam.loop_closure.sparse_loop_edge_keyframes,
                "keyframes nearest the match a closure against a sparse submap is tied to (0: its anchor)");
  d->add_option("--member-check-exclusion", slam2d.slam.loop_closure.member_check_exclusion_m,
                "a sparse submap's keyframe is tied to only if the submap without the views within this distance (m) "
                "places it where it is drawn (< 0: no check)");
  d->add_option("--member-check-near-exclusion", slam2d.slam.loop_closure.member_check_near_exclusion_m,
                "the check runs again without the views within this distance (m) only (≤ 0: once)");
  d->add_option("--member-check-max-turn", slam2d.slam.loop_closure.member_check_max_turn_rad,
                "that check rules out a keyframe the submap turns by more than this (rad)");
  d->add_option("--member-check-max-shift", slam2d.slam.loop_closure.member_check_max_shift_m,
                "that check also rules out a keyframe the submap shifts by more than this (m; 0: the heading alone)");
  d->add_option("--sequential-sigma-m-per-m", slam2d.slam.loop_closure.sequential_sigma_m_per_m,
                "pose graph: growth of a consecutive-keyframe edge's translation sigma with its step (m per m)");
  d->add_option("--sequential-sigma-rad-per-m", slam2d.slam.loop_closure.sequential_sigma_rad_per_m,
                "pose graph: growth of a consecutive-keyframe edge's heading sigma with its step (rad per m)");
  d->add_option("--loop-min-score", slam2d.slam.loop_closure.min_score, "correlative score a loop closure needs");
  d->add_option("--loop-max-candidates", slam2d.slam.loop_closure.max_candidates,
                "submaps a searching keyframe is matched against, nearest first");
  d->add_option("--loop-exclude-recent-submaps", slam2d.slam.loop_closure.exclude_recent_submaps,
                "a trajectory's newest finished submaps it is not matched against");
  d->add_option("--max-loop-window-m", slam2d.slam.loop_closure.max_window_m,
                "cap of the loop-closure search window's half-width, metres");
  d->add_option("--max-loop-window-rad", slam2d.slam.loop_closure.max_window_rad,
                "cap of the loop-closure search window's half-width in heading, radians");
  d->add_option("--loop-support-separation", slam2d.slam.loop_closure.support_min_separation_m,
                "two loop closures support each other only when their queries are this far apart along the path (m)");
  d->add_option("--loop-support-keyframes", slam2d.slam.loop_closure.support_keyframes,
                "keyframes a loop closure that needs support waits for it");
  d->add_option("--loop-support-wait-open-fraction", slam2d.slam.loop_closure.support_wait_open_fraction,
                "on a sparse trajectory a loop closure that needs support also waits this fraction of the distance "
                "travelled without a closure before it (0: keyframes only)");
  d->add_option("--loop-sparse-support-max-keyframes", slam2d.slam.loop_closure.sparse_support_max_keyframes,
                "on a sparse trajectory the most keyframes a loop closure waits for support");
  d->add_option("--max-loop-error-m", slam2d.slam.loop_closure.max_loop_error_m,
                "a loop edge still off by more than this (m) after an optimisation is disabled");
  d->add_option("--loop-ambiguity-margin", slam2d.slam.loop_closure.submap.ambiguity_margin,
                "a loop match is ambiguous when a pose away from it scores within this margin (0: no check)");
  d->add_option("--loop-ambiguous-min-score", slam2d.slam.loop_closure.ambiguous_min_score,
                "correlative score an ambiguous loop match against a dense submap needs");
  d->add_option("--loop-confirm-after", slam2d.slam.loop_closure.confirm_after_s,
                "sensor time (s) a closure one optimisation kept waits for a later one before it is reported");
  d->add_option("--loop-min-points", slam2d.slam.loop_closure.min_match_points,
                "match points a keyframe needs to search for loop closures");
  rmap::bench::ReplayCheckOptions replay;
  replay.shared_data_dir = RMAP_SHARED_DATA_DIR;
  CLI::App* r = app.add_subcommand("replay-check",
                                   "a server's map after `rmap replay` against the map3d / slam2d offline builds");
  r->add_option("--server", replay.server_url, "http://HOST:PORT")->required();
  r->add_option("--token", replay.token, "bearer token (viewer role is enough)");
  r->add_option("--map", replay.map, "the replayed map")->required();
  r->add_option("--scans", replay.scans_source, "the 3D source replayed (as map3d --scans)");
  r->add_option("--resolution", replay.resolution_m, "the 3D map's resolution, metres")->check(CLI::PositiveNumber);
  r->add_option("--grid-step", replay.grid_step_cells, "query every N-th cell centre of the bounds")
      ->check(CLI::Range(1, 1000));
  r->add_option("--log", replay.log_path, "the CARMEN log replayed (as slam2d --log)");
  r->add_option("--robot", replay.robot_id, "the replayed robot (for its trajectory)");
  r->add_option("--json", replay.json_out, "write results as JSON to this file");

  rmap::bench::CalibrationEvalOptions calib;
  calib.lidar_pair_dir = std::string(RMAP_SHARED_DATA_DIR) + "/lidar-intensity/small-gicp-pair";
  CLI::App* c = app.add_subcommand("calib", "2D laser intensity calibration on both simulated scanners, real lidar check");
  c->add_option("--poses", calib.poses, "scans per simulated run")->check(CLI::Range(1, 100000));
  c->add_option("--seed", calib.seed, "building and tour of the calibration run (the test run: seed + 1)");
  c->add_option("--lidar-pair", calib.lidar_pair_dir, "folder with source.ply, target.ply, T_target_source.txt ('' skips)");
  c->add_option("--json", calib.json_out, "write results as JSON to this file");

  rmap::bench::LoopBenchOptions loop;
  CLI::App* l = app.add_subcommand("loop", "place recognition on an image sequence: precision-recall vs ground-truth loops, ms/frame");
  l->add_option("--images", loop.images_dir, "folder of images in frame order (sorted by name)")->required();
  l->add_option("--ground-truth", loop.ground_truth, "'query reference' pairs, 0-based, # comments (omit: timing only)");
  l->add_option("--json", loop.json_out, "write results as JSON to this file");
  l->add_option("--csv-prefix", loop.csv_prefix, "write P_pr_tol<k>.csv, P_frames.csv and P_pr.png");
  l->add_option("--descriptor", loop.descriptor, "binary descriptor")->check(CLI::IsMember({"orb", "brisk", "akaze"}));
  l->add_option("--max-features", loop.max_features, "keypoints per frame at most")->check(CLI::Range(1, 100000));
  l->add_option("--max-frames", loop.max_frames, "only the first N frames (0: all)");
  l->add_option("--threads", loop.threads, "OpenCV threads")->check(CLI::Range(1, 64));
  l->add_option("--resize", [&](const std::vector<std::string>& v) {
       loop.resize_width = std::stoi(v.at(0));
       loop.resize_height = std::stoi(v.at(1));
       return loop.resize_width > 0 && loop.resize_height > 0;
     }, "resize every frame to W H pixels first")->expected(2);
  l->add_option("--min-score", loop.detector.min_score, "acceptance threshold on the detector's score (inlier evidence)");

  // Simulated revisit sequences: the options both loop-sim and loop-compare take.
  auto addSequenceOptions = [](CLI::App* a, rmap::bench::SimSequenceOptions& seq, rmap::loop::PanoramaOptions& pano) {
    a->add_option("--seed", seq.seed, "simulation seed (course, path, noise)");
    a->add_option("--laps", seq.revisit.laps, "laps of the loop course")->check(CLI::Range(1, 100));
    a->add_option("--step", seq.revisit.step_m, "metres between frames")->check(CLI::PositiveNumber);
    a->add_option("--course-size", [&seq](const std::vector<std::string>& v) {
         seq.course.size_x_m = std::stod(v.at(0));
         seq.course.size_y_m = std::stod(v.at(1));
         return true;
       }, "loop course footprint X Y, metres")->expected(2);
    a->add_option("--camera-size", [&seq](const std::vector<std::string>& v) {
         seq.camera.width_px = std::stoi(v.at(0));
         seq.camera.height_px = std::stoi(v.at(1));
         return true;
       }, "camera image W H, pixels")->expected(2);
    a->add_option("--lidar-rings", seq.lidar.rings, "simulated lidar rings")->check(CLI::Range(1, 1024));
    a->add_option("--lidar-columns", seq.lidar.columns, "simulated lidar columns")->check(CLI::Range(1, 16384));
    a->add_option("--panorama-size", [&pano](const std::vector<std::string>& v) {
         pano.width_px = std::stoi(v.at(0));
         pano.height_px = std::stoi(v.at(1));
         return true;
       }, "laser panorama W H, pixels")->expected(2);
  };

  rmap::bench::LoopSimBenchOptions loop_sim;
  CLI::App* ls = app.add_subcommand("loop-sim", "place recognition on a simulated revisit sequence (camera or laser intensity)");
  ls->add_option("--modality", loop_sim.modality, "camera or laser")->check(CLI::IsMember({"camera", "laser"}));
  ls->add_flag("--dark", loop_sim.dark, "revisit laps in the dark (light ~0 + sensor noise; laser unaffected)");
  ls->add_option("--projection", loop_sim.projection, "laser panorama projection")
      ->check(CLI::IsMember({"equirectangular", "ring"}));
  ls->add_option("--descriptor", loop_sim.descriptor, "binary descriptor")->check(CLI::IsMember({"orb", "brisk", "akaze"}));
  ls->add_option("--verification", loop_sim.verification,
                 "laser: rigid3d = rmapd's panorama options (keypoints lifted to metres, two consecutive frames), "
                 "fundamental = the detector's defaults (image only)")
      ->check(CLI::IsMember({"rigid3d", "fundamental"}));
  ls->add_option("--threads", loop_sim.threads, "OpenCV threads")->check(CLI::Range(1, 64));
  ls->add_option("--json", loop_sim.json_out, "write results as JSON to this file");
  addSequenceOptions(ls, loop_sim.sequence, loop_sim.panorama);

  rmap::bench::LoopCompareOptions compare;
  compare.lidar_pair_dir = std::string(RMAP_SHARED_DATA_DIR) + "/lidar-intensity/small-gicp-pair";
  CLI::App* lc = app.add_subcommand("loop-compare",
                                    "projection models x descriptors on simulated lidar-intensity panoramas, plus a real lidar pair");
  lc->add_option("--tolerance", compare.tolerance, "frames, for recall at 100 % precision")->check(CLI::NonNegativeNumber);
  lc->add_option("--lidar-pair", compare.lidar_pair_dir, "folder with source.ply, target.ply, T_target_source.txt ('' skips)");
  lc->add_option("--threads", compare.threads, "OpenCV threads")->check(CLI::Range(1, 64));
  lc->add_option("--json", compare.json_out, "write results as JSON to this file");
  addSequenceOptions(lc, compare.sequence, compare.panorama);

  CLI11_PARSE(app, argc, argv);
  try {
    if (m->parsed()) return rmap::bench::runMap3dBench(map3d);
    if (s->parsed()) return rmap::bench::runServerBench(server);
    if (lo->parsed()) return rmap::bench::runLoadBench(load);
    if (d->parsed()) {
      slam2d.slam.loop_closure.enabled = loop_closure == "on";
      return rmap::bench::runSlam2dBench(slam2d);
    }
    if (c->parsed()) return rmap::bench::runCalibrationBench(calib);
    if (r->parsed()) {
      if (replay.scans_source.empty() == replay.log_path.empty()) throw std::runtime_error("replay-check needs --scans or --log");
      if (!replay.log_path.empty() && replay.robot_id.empty()) throw std::runtime_error("replay-check --log needs --robot");
      return rmap::bench::runReplayCheck(replay);
    }
    if (l->parsed()) return rmap::bench::runLoopBench(loop);
    if (ls->parsed()) return rmap::bench::runLoopSimBench(loop_sim);
    if (lc->parsed()) return rmap::bench::runLoopCompareBench(compare);
  } catch (const std::exception& e) {
    std::cerr << "rmap-bench: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
