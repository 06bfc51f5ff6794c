#include "loop_sim/loop_sim_bench.h"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <numbers>
#include <nlohmann/json.hpp>
#include <opencv2/features2d.hpp>
#include <stdexcept>

#include "common/machine.h"
#include "common/lidar_pair.h"
#include "datasets/ply_cloud.h"
#include "loop/point_image.h"
#include "loop_sim/detector_run.h"

namespace rmap::bench {
namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

void writeJson(const std::string& path, const json& j) {
  std::ofstream out(path);
  if (!out || !(out << j.dump(2) << "\n")) throw std::runtime_error("cannot write " + path);
  std::cout << "wrote " << path << std::endl;
}

std::string projectionName(loop::PanoramaProjection p) {
  return p == loop::PanoramaProjection::kEquirectangular ? "equirectangular" : "ring";
}

loop::PanoramaOptions panoramaFor(loop::PanoramaOptions o, loop::PanoramaProjection projection, int rings) {
  o.projection = projection;
  if (projection == loop::PanoramaProjection::kRingByColumn && o.ring_elevations_rad.empty() && o.ring_count == 0) {
    o.ring_count = rings;
  }
  return o;
}

json sequenceJson(const SimRevisitSequence& seq) {
  size_t pairs = 0;
  for (const auto& [q, refs] : seq.truth()) pairs += refs.size();
  const SimSequenceOptions& o = seq.options();
  return {{"seed", o.seed},
          {"frames", seq.size()},
          {"laps", o.revisit.laps},
          {"step_m", o.revisit.step_m},
          {"course_m", {o.course.size_x_m, o.course.size_y_m}},
          {"truth_pairs", pairs},
          {"truth_max_distance_m", o.truth.max_distance_m},
          {"truth_max_heading_rad", o.truth.max_heading_rad}};
}

struct RealPairRow {
  std::string projection, descriptor;
  size_t keypoints_source = 0, keypoints_target = 0, matches = 0, agreeing = 0, chance = 0;
  double extract_ms = 0.0, project_ms = 0.0;
  /// rmapd's verification of the pair (keypoints lifted to their points, 3D rigid RANSAC) and
  /// its fitted motion against the known one.
  int rigid3d_matches = 0, rigid3d_inliers = 0;
  double rigid3d_error_m = 0.0, rigid3d_error_deg = 0.0;
};

/// The keypoints of `all` that have a point near them, and those points.
std::pair<loop::Features, std::vector<Eigen::Vector3f>> liftedFeatures(const loop::Features& all,
                                                                       const cv::Mat& points_m, int radius_px) {
  std::pair<loop::Features, std::vector<Eigen::Vector3f>> out;
  for (size_t i = 0; i < all.keypoints.size(); ++i) {
    const std::optional<Eigen::Vector3f> p = loop::pointNear(points_m, all.keypoints[i].pt, radius_px);
    if (!p) continue;
    out.first.keypoints.push_back(all.keypoints[i]);
    out.first.descriptors.push_back(all.descriptors.row(static_cast<int>(i)));
    out.second.push_back(*p);
  }
  return out;
}

std::vector<RealPairRow> realPairCheck(const LoopCompareOptions& o) {
  const std::string dir = o.lidar_pair_dir;
  const Eigen::Matrix4d target_from_source = readTransform(dir + "/T_target_source.txt");
  const char* names[2] = {"source.ply", "target.ply"};
  datasets::PlyCloud clouds[2];
  for (int s = 0; s < 2; ++s) clouds[s] = datasets::readPlyCloud(dir + "/" + names[s]);
  std::vector<RealPairRow> rows;
  for (const loop::PanoramaProjection projection :
       {loop::PanoramaProjection::kEquirectangular, loop::PanoramaProjection::kRingByColumn}) {
    // The real sensor's rings come from the source scan's elevation gaps; the
    // equirectangular field of view spans them (half a ring spacing beyond).
    const std::vector<float> rings = loop::estimateRingElevations(clouds[0].points_m, 0, o.panorama.ring_gap_rad);
    if (rings.size() < 2) throw std::runtime_error(dir + ": fewer than 2 laser rings found in source.ply");
    const double half_spacing = 0.5 * (rings.back() - rings.front()) / static_cast<double>(rings.size() - 1);
    loop::PanoramaOptions po = o.panorama;
    po.projection = projection;
    po.ring_elevations_rad = rings;
    po.fov_up_rad = rings.back() + half_spacing;
    po.fov_down_rad = rings.front() - half_spacing;
    cv::Mat images[2], points[2];
    double project_ms = 0.0;
    for (int s = 0; s < 2; ++s) {
      const auto t0 = Clock::now();
      cv::Mat index;
      images[s] = loop::projectPanorama(clouds[s].points_m, intensityOf(clouds[s], names[s]), po, index);
      points[s] = loop::panoramaPoints(index, clouds[s].points_m);
      project_ms += 0.5 * msSince(t0);
    }
    const int radius = std::max(2, po.height_px / static_cast<int>(rings.size()));
    for (const loop::DescriptorType type :
         {loop::DescriptorType::kOrb, loop::DescriptorType::kBrisk, loop::DescriptorType::kAkaze}) {
      const auto extractor = loop::makeExtractor(type, 500);
      RealPairRow row{projectionName(projection), loop::toString(type)};
      row.project_ms = project_ms;
      loop::Features f[2];
      for (int s = 0; s < 2; ++s) {
        const auto t0 = Clock::now();
        f[s] = extractor->extract(images[s]);
        row.extract_ms += 0.5 * msSince(t0);
      }
      row.keypoints_source = f[0].keypoints.size();
      row.keypoints_target = f[1].keypoints.size();
      if (f[0].descriptors.empty() || f[1].descriptors.empty()) {
        rows.push_back(row);
        continue;
      }
      std::vector<cv::DMatch> matches;
      cv::BFMatcher(cv::NORM_HAMMING, true).match(f[0].descriptors, f[1].descriptors, matches);
      std::vector<std::pair<Eigen::Vector3f, Eigen::Vector3f>> lifted;  // (source point, target point) of each match
      for (const cv::DMatch& m : matches) {
        const auto ps = loop::pointNear(points[0], f[0].keypoints[m.queryIdx].pt, radius);
        const auto pt = loop::pointNear(points[1], f[1].keypoints[m.trainIdx].pt, radius);
        if (ps && pt) lifted.emplace_back(*ps, *pt);
      }
      auto agree = [&](const Eigen::Vector3f& ps, const Eigen::Vector3f& pt) {
        const Eigen::Vector3d moved = (target_from_source * ps.cast<double>().homogeneous()).head<3>();
        return (moved - pt.cast<double>()).norm() <= o.agree_m;
      };
      row.matches = lifted.size();
      for (size_t k = 0; k < lifted.size(); ++k) {
        row.agreeing += agree(lifted[k].first, lifted[k].second);
        // Chance level: the same keypoints paired with another match's target.
        row.chance += agree(lifted[k].first, lifted[(k + lifted.size() / 2) % lifted.size()].second);
      }
      const auto source = liftedFeatures(f[0], points[0], o.detector.point_lift_radius_px);
      const auto target = liftedFeatures(f[1], points[1], o.detector.point_lift_radius_px);
      const loop::Verification v = loop::verifyRigid3d(source.second, source.first.descriptors, target.second,
                                                       target.first.descriptors, o.detector.verification);
      row.rigid3d_matches = v.matches;
      row.rigid3d_inliers = v.inliers;
      const Eigen::Isometry3d error = Eigen::Isometry3d(target_from_source).inverse() * v.reference_from_query;
      row.rigid3d_error_m = error.translation().norm();
      row.rigid3d_error_deg = Eigen::AngleAxisd(error.linear()).angle() * 180.0 / std::numbers::pi;
      rows.push_back(row);
    }
  }
  return rows;
}

}  // namespace

loop::PanoramaProjection projectionFromString(const std::string& name) {
  if (name == "equirectangular") return loop::PanoramaProjection::kEquirectangular;
  if (name == "ring") return loop::PanoramaProjection::kRingByColumn;
  throw std::invalid_argument("unknown projection '" + name + "' (equirectangular | ring)");
}

int runLoopSimBench(const LoopSimBenchOptions& options) {
  if (options.modality != "camera" && options.modality != "laser") {
    throw std::invalid_argument("loop-sim: --modality must be camera or laser");
  }
  cv::setNumThreads(options.threads);
  const bool laser = options.modality == "laser";
  SimSequenceOptions so = options.sequence;
  so.dark = options.dark;
  const SimRevisitSequence seq(so);
  const loop::PanoramaOptions panorama =
      panoramaFor(options.panorama, projectionFromString(options.projection), so.lidar.rings);
  panorama.validate();
  // Laser panoramas as rmapd takes them (verified in metres, through their points), or by image only.
  const loop::LoopDetectorOptions detector =
      laser && options.verification == "rigid3d" ? loop::panoramaDetectorOptions() : options.detector;

  double render_ms = 0.0, project_ms = 0.0;
  cv::Size size;
  const auto frame = [&](size_t i) {
    const auto t0 = Clock::now();
    loop::PlaceImage image(cv::Mat{});
    if (laser) {
      const SensorScan scan = seq.lidarScan(i);
      render_ms += msSince(t0);
      const auto t1 = Clock::now();
      cv::Mat index;
      image.gray = loop::projectPanorama(scan.points_sensor, scan.intensities, panorama, index);
      if (detector.verification.model == loop::GeometricModel::kRigid3d) {
        image.points_m = loop::panoramaPoints(index, scan.points_sensor);
      }
      project_ms += msSince(t1);
    } else {
      image.gray = seq.cameraImage(i);
      render_ms += msSince(t0);
    }
    size = image.gray.size();
    return image;
  };
  const DetectorRun run =
      runDetector(frame, seq.size(), loop::descriptorTypeFromString(options.descriptor), detector);
  json score = scoreJson(run, seq.truth(), options.tolerances);

  json j = {{"benchmark", "loop-sim"},
            {"modality", options.modality},
            {"dark", options.dark},
            {"descriptor", options.descriptor},
            {"image_size", {size.width, size.height}},
            {"sequence", sequenceJson(seq)},
            {"frames", seq.size()},
            {"render_ms_per_frame_mean", render_ms / static_cast<double>(seq.size())},
            {"opencv_threads", options.threads},
            {"machine", machineJson()}};
  if (laser) {
    j["projection"] = projectionName(panorama.projection);
    j["verification"] = options.verification;
    j["project_ms_per_frame_mean"] = project_ms / static_cast<double>(seq.size());
  }
  j.update(score);

  const std::string projection = laser ? projectionName(panorama.projection) : std::string("image");
  std::printf("loop-sim %s%s (%s), %s: %zu frames %dx%d, %zu loop queries, %zu candidates, %zu accepted, %zu words\n",
              options.modality.c_str(), options.dark ? " dark revisits" : "", projection.c_str(),
              options.descriptor.c_str(), seq.size(),
              size.width, size.height, seq.truth().size(), run.swept.size(), run.accepted.size(), run.vocabulary_words);
  for (int64_t k : options.tolerances) {
    const std::string key = "tol" + std::to_string(k);
    std::printf("k=%-3lld recall@100%%P %6.2f %%  AUC %.3f   accepted: precision %6.2f %% recall %6.2f %%\n",
                static_cast<long long>(k), 100.0 * score["recall_at_100_precision"][key].get<double>(),
                score["auc"][key].get<double>(), 100.0 * score["precision"][key].get<double>(),
                100.0 * score["recall"][key].get<double>());
  }
  std::printf("detector ms/frame: mean %.2f p95 %.2f (thread CPU mean %.2f); rendering %.1f, projection %.1f ms/frame\n",
              meanOf(run.wall_ms), quantileOf(run.wall_ms, 0.95), meanOf(run.cpu_ms),
              render_ms / static_cast<double>(seq.size()), project_ms / static_cast<double>(seq.size()));
  if (!options.json_out.empty()) writeJson(options.json_out, j);
  return 0;
}

int runLoopCompareBench(const LoopCompareOptions& options) {
  cv::setNumThreads(options.threads);
  const SimRevisitSequence seq(options.sequence);
  const std::vector<loop::PanoramaProjection> projections{loop::PanoramaProjection::kEquirectangular,
                                                          loop::PanoramaProjection::kRingByColumn};
  // The same scans for every cell of the table.
  std::vector<std::vector<cv::Mat>> images(projections.size());
  std::vector<double> project_ms(projections.size(), 0.0);
  for (size_t i = 0; i < seq.size(); ++i) {
    const SensorScan scan = seq.lidarScan(i);
    for (size_t p = 0; p < projections.size(); ++p) {
      const auto t0 = Clock::now();
      images[p].push_back(loop::projectPanorama(scan.points_sensor, scan.intensities,
                                                panoramaFor(options.panorama, projections[p], options.sequence.lidar.rings)));
      project_ms[p] += msSince(t0) / static_cast<double>(seq.size());
    }
  }
  const std::string key = "tol" + std::to_string(options.tolerance);
  json rows = json::array();
  std::printf("simulated lidar-intensity panoramas: %zu frames, %zu loop queries, k = %lld\n\n", seq.size(),
              seq.truth().size(), static_cast<long long>(options.tolerance));
  std::printf("| projection | descriptor | recall@100%%P | precision | recall | ms/frame (detector) | CPU ms/frame | ms/frame (projection) |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (size_t p = 0; p < projections.size(); ++p) {
    for (const loop::DescriptorType type :
         {loop::DescriptorType::kOrb, loop::DescriptorType::kBrisk, loop::DescriptorType::kAkaze}) {
      const DetectorRun run =
          runDetector([&](size_t i) { return images[p][i]; }, seq.size(), type, options.detector);
      json score = scoreJson(run, seq.truth(), {options.tolerance});
      score["projection"] = projectionName(projections[p]);
      score["descriptor"] = loop::toString(type);
      score["project_ms_per_frame_mean"] = project_ms[p];
      std::printf("| %s | %s | %.1f %% | %.1f %% | %.1f %% | %.1f | %.1f | %.1f |\n", projectionName(projections[p]).c_str(),
                  loop::toString(type).c_str(), 100.0 * score["recall_at_100_precision"][key].get<double>(),
                  100.0 * score["precision"][key].get<double>(), 100.0 * score["recall"][key].get<double>(),
                  score["ms_per_frame_mean"].get<double>(), score["cpu_ms_per_frame_mean"].get<double>(), project_ms[p]);
      std::fflush(stdout);
      rows.push_back(score);
    }
  }
  json j = {{"benchmark", "loop-compare"},
            {"sequence", sequenceJson(seq)},
            {"tolerance", options.tolerance},
            {"image_size", {options.panorama.width_px, options.panorama.height_px}},
            {"simulated", rows},
            {"opencv_threads", options.threads},
            {"machine", machineJson()}};
  if (!options.lidar_pair_dir.empty()) {
    json real = json::array();
    std::printf("\nreal lidar pair %s: mutual-nearest matches whose 3D points agree within %.2f m\n\n",
                options.lidar_pair_dir.c_str(), options.agree_m);
    std::printf("| projection | descriptor | keypoints (source / target) | matches | agreeing | share | chance share | "
                "rigid3d matches / inliers | rigid3d fit error m / ° | ms (extract) |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
    for (const RealPairRow& r : realPairCheck(options)) {
      const double share = r.matches ? static_cast<double>(r.agreeing) / static_cast<double>(r.matches) : 0.0;
      const double chance = r.matches ? static_cast<double>(r.chance) / static_cast<double>(r.matches) : 0.0;
      std::printf("| %s | %s | %zu / %zu | %zu | %zu | %.1f %% | %.1f %% | %d / %d | %.3f / %.2f | %.1f |\n",
                  r.projection.c_str(), r.descriptor.c_str(), r.keypoints_source, r.keypoints_target, r.matches,
                  r.agreeing, 100.0 * share, 100.0 * chance, r.rigid3d_matches, r.rigid3d_inliers, r.rigid3d_error_m,
                  r.rigid3d_error_deg, r.extract_ms);
      real.push_back({{"projection", r.projection},
                      {"descriptor", r.descriptor},
                      {"keypoints", {r.keypoints_source, r.keypoints_target}},
                      {"matches", r.matches},
                      {"agreeing", r.agreeing},
                      {"agreeing_share", share},
                      {"chance_share", chance},
                      {"rigid3d", {{"matches", r.rigid3d_matches},
                                   {"inliers", r.rigid3d_inliers},
                                   {"fit_error_m", r.rigid3d_error_m},
                                   {"fit_error_deg", r.rigid3d_error_deg}}},
                      {"extract_ms", r.extract_ms},
                      {"project_ms", r.project_ms}});
    }
    j["real_pair"] = {{"dir", options.lidar_pair_dir}, {"agree_m", options.agree_m}, {"rows", real}};
  }
  if (!options.json_out.empty()) writeJson(options.json_out, j);
  return 0;
}

}  // namespace rmap::bench
