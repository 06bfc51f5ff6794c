#include "loop/loop_detector.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "loop/binary_descriptor.h"
#include "loop/descriptor_matching.h"
#include "loop/point_image.h"

namespace rmap::loop {

void LoopDetectorOptions::validate() const {
  vocabulary.validate();
  verification.validate();
  auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("LoopDetectorOptions: ") + what);
  };
  require(track_distance_fraction > 0.0 && track_distance_fraction < 0.5, "track_distance_fraction must be in (0, 0.5)");
  require(track_ratio > 0.0 && track_ratio <= 1.0, "track_ratio must be in (0, 1]");
  require(purge_after_frames >= 0, "purge_after_frames must be >= 0");
  require(exclusion_window_frames >= 1, "exclusion_window_frames must be >= 1");
  require(min_similarity >= 0.0 && min_similarity <= 1.0, "min_similarity must be in [0, 1]");
  require(island_score_fraction > 0.0 && island_score_fraction <= 1.0, "island_score_fraction must be in (0, 1]");
  require(island_gap_frames >= 1, "island_gap_frames must be >= 1");
  require(temporal_consistency_frames >= 1, "temporal_consistency_frames must be >= 1");
  require(verify_islands >= 1, "verify_islands must be >= 1");
  require(verify_per_island >= 1, "verify_per_island must be >= 1");
  require(std::isfinite(inlier_floor) && inlier_floor >= 0.0, "inlier_floor must be finite and >= 0");
  require(evidence_decay >= 0.0 && evidence_decay < 1.0, "evidence_decay must be in [0, 1)");
  require(std::isfinite(min_score), "min_score must be finite");
  require(point_lift_radius_px >= 0, "point_lift_radius_px must be >= 0");
}

LoopDetectorOptions panoramaDetectorOptions() {
  LoopDetectorOptions o;
  o.verification.model = GeometricModel::kRigid3d;
  o.temporal_consistency_frames = 2;
  return o;
}

namespace {

constexpr int kMinImageSidePx = 32;

const LoopDetectorOptions& validated(const LoopDetectorOptions& o) {
  o.validate();
  return o;
}

std::unique_ptr<FeatureExtractor> orDefault(std::unique_ptr<FeatureExtractor> extractor) {
  return extractor ? std::move(extractor) : makeExtractor(DescriptorType::kOrb);
}

}  // namespace

LoopDetector::LoopDetector(LoopDetectorOptions options, std::unique_ptr<FeatureExtractor> extractor)
    : options_(validated(options)),
      extractor_(orDefault(std::move(extractor))),
      vocabulary_(extractor_->descriptorBytes(), options_.vocabulary) {}

FrameResult LoopDetector::addFrame(const cv::Mat& gray) { return addFrame(PlaceImage(gray)); }

FrameResult LoopDetector::addFrame(const PlaceImage& image, const std::string& stream) {
  checkGrayImage(image.gray, kMinImageSidePx);
  if (image.points_m.empty()) {
    if (options_.verification.model == GeometricModel::kRigid3d) {
      throw std::invalid_argument("LoopDetector: 3D rigid verification needs the image's point image");
    }
    return addFeatures(extractor_->extract(image.gray), {}, stream);
  }
  if (!isPointImage(image.points_m, image.gray.size())) {
    throw std::invalid_argument("LoopDetector: the point image must be CV_32FC3 of the image's size");
  }
  const Features all = extractor_->extract(image.gray);
  Features kept;
  std::vector<Eigen::Vector3f> points;
  for (size_t i = 0; i < all.keypoints.size(); ++i) {
    const std::optional<Eigen::Vector3f> p =
        pointNear(image.points_m, all.keypoints[i].pt, options_.point_lift_radius_px);
    if (!p) continue;
    kept.keypoints.push_back(all.keypoints[i]);
    kept.descriptors.push_back(all.descriptors.row(static_cast<int>(i)));
    points.push_back(*p);
  }
  return addFeatures(kept, std::move(points), stream);
}

size_t LoopDetector::streamId(const std::string& name) {
  const auto [it, added] = stream_ids_.try_emplace(name, streams_.size());
  if (added) streams_.emplace_back();
  return it->second;
}

FrameResult LoopDetector::addFeatures(const Features& features, std::vector<Eigen::Vector3f> points_m,
                                      const std::string& stream_name) {
  const cv::Mat& d = features.descriptors;
  const auto n = static_cast<int>(features.keypoints.size());
  if (n > 0 && (d.type() != CV_8UC1 || d.cols != extractor_->descriptorBytes() || d.rows != n)) {
    throw std::invalid_argument("LoopDetector: descriptors must be CV_8U rows of " +
                                std::to_string(extractor_->descriptorBytes()) + " bytes (" +
                                toString(extractor_->type()) + "), one per keypoint");
  }
  if (n == 0 && !d.empty()) throw std::invalid_argument("LoopDetector: descriptors without keypoints");
  const bool rigid3d = options_.verification.model == GeometricModel::kRigid3d;
  if (rigid3d && (points_m.size() != static_cast<size_t>(n) ||
                  !std::all_of(points_m.begin(), points_m.end(), [](const Eigen::Vector3f& p) { return p.allFinite(); }))) {
    throw std::invalid_argument("LoopDetector: 3D rigid verification needs one finite point per keypoint");
  }

  const int blocks = descriptorBlocks(extractor_->descriptorBytes());
  std::vector<uint64_t> packed(static_cast<size_t>(n) * blocks);
  for (int i = 0; i < n; ++i) packDescriptor(d.ptr<uint8_t>(i), d.cols, packed.data() + static_cast<size_t>(i) * blocks);

  const auto frame = static_cast<int64_t>(frames_.size());
  const size_t stream_id = streamId(stream_name);
  Stream& stream = streams_[stream_id];
  const auto ordinal = static_cast<int64_t>(stream.frames.size());
  std::vector<WordId> words = assignWords(features, packed, stream);
  std::vector<FrameScore> scores = index_.score(words, frame);
  // The stream's own recent frames look alike without being loops; other streams' may be the same place.
  const int64_t window_start = ordinal >= options_.exclusion_window_frames
                                   ? stream.frames[ordinal - options_.exclusion_window_frames]
                                   : 0;
  std::erase_if(scores, [&](const FrameScore& s) {
    const StoredFrame& f = frames_[s.frame];
    if (options_.exclusion_window_all_streams) return s.frame >= window_start;
    return f.stream == stream_id && f.ordinal >= ordinal - options_.exclusion_window_frames;
  });

  StoredFrame stored;
  stored.stream = stream_id;
  stored.ordinal = ordinal;
  stored.points.reserve(n);
  for (const cv::KeyPoint& k : features.keypoints) stored.points.push_back(k.pt);
  stored.descriptors = n > 0 ? d.clone() : cv::Mat(0, extractor_->descriptorBytes(), CV_8U);
  if (rigid3d) stored.points_m = std::move(points_m);

  // Verify the best frames of the top islands, and of the island the previous frame's loop predicts.
  std::vector<Island> candidates = islands(scores);
  if (candidates.size() > static_cast<size_t>(options_.verify_islands)) candidates.resize(options_.verify_islands);
  if (const std::optional<Island> predicted = predictedIsland(scores, stream_id, ordinal, window_start)) {
    candidates.push_back(*predicted);
  }
  std::optional<LoopCandidate> best;
  std::vector<int64_t> verified;
  for (Island& island : candidates) {
    std::sort(island.members.begin(), island.members.end(),
              [](const FrameScore& x, const FrameScore& y) { return x.score > y.score; });
    if (island.members.size() > static_cast<size_t>(options_.verify_per_island)) {
      island.members.resize(options_.verify_per_island);
    }
    for (const FrameScore& m : island.members) {
      if (std::find(verified.begin(), verified.end(), m.frame) != verified.end()) continue;  // islands may overlap
      verified.push_back(m.frame);
      const StoredFrame& ref = frames_[m.frame];
      const Verification v =
          rigid3d ? verifyRigid3d(stored.points_m, stored.descriptors, ref.points_m, ref.descriptors,
                                  options_.verification)
                  : verifyGeometry(stored.points, stored.descriptors, ref.points, ref.descriptors, options_.verification);
      if (!best || v.inliers > best->inliers) {
        best = LoopCandidate{frame, m.frame, 0.0, v.inliers, v.matches, m.score, std::nullopt, std::nullopt};
        if (rigid3d && v.inliers > 0) best->reference_from_query = v.reference_from_query;
        if (v.inliers > 0) best->reference_from_query_px = v.reference_from_query_px;
      }
    }
  }
  if (best) {
    best->score = best->inliers - options_.inlier_floor;
    const std::optional<LoopCandidate>& previous = stream.recent.empty() ? std::nullopt : stream.recent.back();
    if (best->score > 0.0 && previous && continues(*previous, best->reference_frame)) {
      best->score += options_.evidence_decay * std::max(0.0, previous->score);
    }
  }

  FrameResult result;
  result.frame = frame;
  if (best && temporallyConsistent(stream, best->reference_frame)) {
    result.best = best;
    result.accepted = best->score >= options_.min_score;
  }

  index_.addFrame(words);
  frames_.push_back(std::move(stored));
  stream.frames.push_back(frame);
  stream.previous_words = std::move(words);
  stream.recent.push_back(best);
  while (stream.recent.size() > static_cast<size_t>(std::max(1, options_.temporal_consistency_frames - 1))) {
    stream.recent.pop_front();
  }
  purge(stream, ordinal);
  return result;
}

std::vector<WordId> LoopDetector::assignWords(const Features& features, const std::vector<uint64_t>& packed,
                                              Stream& stream) {
  const int n = static_cast<int>(features.keypoints.size());
  const int blocks = descriptorBlocks(extractor_->descriptorBytes());
  std::vector<WordId> words(n, -1);
  std::vector<bool> moved(n, false);  // reinforced, and its descriptor changed
  if (!stream.frames.empty()) {
    const int track_bits = static_cast<int>(options_.track_distance_fraction * vocabulary_.descriptorBits());
    for (const auto& [i, j] : mutualMatches(features.descriptors, frames_[stream.frames.back()].descriptors,
                                            track_bits, options_.track_ratio)) {
      if (vocabulary_.alive(stream.previous_words[j])) words[i] = stream.previous_words[j];
    }
  }
  std::vector<WordId> created;
  for (int i = 0; i < n; ++i) {
    const uint64_t* p = packed.data() + static_cast<size_t>(i) * blocks;
    if (words[i] < 0) words[i] = vocabulary_.match(p);
    if (words[i] >= 0) {
      moved[i] = vocabulary_.reinforce(words[i], p);
    } else {
      words[i] = vocabulary_.add(p);
      created.push_back(words[i]);
    }
  }
  // A reinforced word that moved onto another word absorbs it (the one seen more keeps its id).
  for (int i = 0; i < n; ++i) {
    const WordId w = words[i];
    if (!moved[i] || !vocabulary_.alive(w)) continue;
    const WordId other = vocabulary_.mergePartner(w);
    if (other < 0) continue;
    const bool keep_w = vocabulary_.observations(w) >= vocabulary_.observations(other);
    const WordId keep = keep_w ? w : other, gone = keep_w ? other : w;
    vocabulary_.merge(keep, gone);
    index_.mergeWords(keep, gone);
    std::replace(words.begin(), words.end(), gone, keep);
  }
  if (options_.purge_after_frames > 0) {
    stream.new_words.emplace_back(static_cast<int64_t>(stream.frames.size()), std::move(created));
  }
  return words;
}

std::vector<LoopDetector::Island> LoopDetector::islands(std::vector<FrameScore> scores) const {
  double top = 0.0;
  for (const FrameScore& s : scores) top = std::max(top, s.score);
  std::vector<Island> out;
  if (top < options_.min_similarity || top <= 0.0) return out;
  const double floor = std::max(options_.min_similarity, options_.island_score_fraction * top);
  std::erase_if(scores, [&](const FrameScore& s) { return s.score < floor; });
  // Frame indices grow with each stream's ordinals: sorted by stream then index, each stream's run is in its order.
  std::sort(scores.begin(), scores.end(), [&](const FrameScore& a, const FrameScore& b) {
    const size_t sa = frames_[a.frame].stream, sb = frames_[b.frame].stream;
    return sa != sb ? sa < sb : a.frame < b.frame;
  });
  for (const FrameScore& s : scores) {
    const StoredFrame& f = frames_[s.frame];
    if (out.empty() || f.stream != out.back().stream || f.ordinal - out.back().last >= options_.island_gap_frames) {
      out.emplace_back();
      out.back().stream = f.stream;
      out.back().first = f.ordinal;
    }
    Island& island = out.back();
    island.last = f.ordinal;
    island.score += s.score;
    island.members.push_back(s);
  }
  std::sort(out.begin(), out.end(), [](const Island& a, const Island& b) { return a.score > b.score; });
  return out;
}

std::optional<LoopDetector::Island> LoopDetector::predictedIsland(const std::vector<FrameScore>& scores,
                                                                  size_t stream_id, int64_t own_frames,
                                                                  int64_t window_start) const {
  const Stream& own = streams_[stream_id];
  if (own.recent.empty() || !own.recent.back() || own.recent.back()->score < options_.min_score) return std::nullopt;
  // The stream's previous frame closed a loop on r: this one most likely closes on the frames
  // around r's successor in r's stream.
  const StoredFrame& reference = frames_[own.recent.back()->reference_frame];
  const Stream& theirs = streams_[reference.stream];
  const int64_t r = reference.ordinal + 1;
  int64_t last = std::min<int64_t>(r + options_.island_gap_frames, static_cast<int64_t>(theirs.frames.size()) - 1);
  if (reference.stream == stream_id) last = std::min<int64_t>(last, own_frames - options_.exclusion_window_frames - 1);
  if (options_.exclusion_window_all_streams) {
    while (last >= 0 && theirs.frames[last] >= window_start) --last;
  }
  const int64_t first = std::max<int64_t>(0, r - options_.island_gap_frames);
  if (last < first) return std::nullopt;
  Island island;
  island.stream = reference.stream;
  island.first = first;
  island.last = last;
  for (const FrameScore& s : scores) {
    const StoredFrame& f = frames_[s.frame];
    if (f.stream == reference.stream && f.ordinal >= first && f.ordinal <= last) {
      island.members.push_back(s);
      island.score += s.score;
    }
  }
  if (island.members.empty()) island.members.push_back({theirs.frames[std::clamp(r, first, last)], 0.0});
  return island;
}

bool LoopDetector::continues(const LoopCandidate& earlier, int64_t reference) const {
  const StoredFrame &a = frames_[earlier.reference_frame], &b = frames_[reference];
  return earlier.inliers > 0 && a.stream == b.stream && std::abs(a.ordinal - b.ordinal) <= options_.island_gap_frames;
}

bool LoopDetector::temporallyConsistent(const Stream& stream, int64_t reference) const {
  const size_t needed = static_cast<size_t>(options_.temporal_consistency_frames - 1);
  if (stream.recent.size() < needed) return false;
  int64_t later = reference;
  for (size_t k = 0; k < needed; ++k) {
    const std::optional<LoopCandidate>& earlier = stream.recent[stream.recent.size() - 1 - k];
    if (!earlier || !continues(*earlier, later)) return false;
    later = earlier->reference_frame;
  }
  return true;
}

void LoopDetector::purge(Stream& stream, int64_t ordinal) {
  while (!stream.new_words.empty() && stream.new_words.front().first + options_.purge_after_frames <= ordinal) {
    for (WordId w : stream.new_words.front().second) {
      if (vocabulary_.alive(w) && index_.documentFrequency(w) <= 1) {
        vocabulary_.remove(w);
        index_.removeWord(w);
      }
    }
    stream.new_words.pop_front();
  }
}

}  // namespace rmap::loop
