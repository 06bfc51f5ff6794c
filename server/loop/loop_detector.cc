#include "loop/loop_detector.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "loop/binary_descriptor.h"
#include "loop/descriptor_matching.h"

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
  require(verify_per_island >= 1, "verify_per_island must be >= 1");
  require(std::isfinite(min_inliers) && min_inliers >= 0.0, "min_inliers must be finite and >= 0");
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

FrameResult LoopDetector::addFrame(const cv::Mat& gray) {
  checkGrayImage(gray, kMinImageSidePx);
  return addFeatures(extractor_->extract(gray));
}

FrameResult LoopDetector::addFeatures(const Features& features) {
  const cv::Mat& d = features.descriptors;
  const auto n = static_cast<int>(features.keypoints.size());
  if (n > 0 && (d.type() != CV_8UC1 || d.cols != extractor_->descriptorBytes() || d.rows != n)) {
    throw std::invalid_argument("LoopDetector: descriptors must be CV_8U rows of " +
                                std::to_string(extractor_->descriptorBytes()) + " bytes (" +
                                toString(extractor_->type()) + "), one per keypoint");
  }
  if (n == 0 && !d.empty()) throw std::invalid_argument("LoopDetector: descriptors without keypoints");

  const int blocks = descriptorBlocks(extractor_->descriptorBytes());
  std::vector<uint64_t> packed(static_cast<size_t>(n) * blocks);
  for (int i = 0; i < n; ++i) packDescriptor(d.ptr<uint8_t>(i), d.cols, packed.data() + static_cast<size_t>(i) * blocks);

  const auto frame = static_cast<int64_t>(frames_.size());
  std::vector<WordId> words = assignWords(features, packed);
  const std::optional<Island> island = bestIsland(words, frame);

  StoredFrame stored;
  stored.points.reserve(n);
  for (const cv::KeyPoint& k : features.keypoints) stored.points.push_back(k.pt);
  stored.descriptors = n > 0 ? d.clone() : cv::Mat(0, extractor_->descriptorBytes(), CV_8U);

  FrameResult result;
  result.frame = frame;
  if (island && temporallyConsistent(island)) {
    std::vector<FrameScore> members = island->members;
    std::sort(members.begin(), members.end(), [](const FrameScore& a, const FrameScore& b) { return a.score > b.score; });
    members.resize(std::min<size_t>(members.size(), options_.verify_per_island));
    LoopCandidate best;
    for (const FrameScore& m : members) {
      const StoredFrame& ref = frames_[m.frame];
      const Verification v =
          verifyGeometry(stored.points, stored.descriptors, ref.points, ref.descriptors, options_.verification);
      if (best.reference_frame < 0 || v.inliers > best.inliers) {
        best.query_frame = frame;
        best.reference_frame = m.frame;
        best.inliers = v.inliers;
        best.score = v.inliers;
      }
    }
    result.best = best;
    result.accepted = best.score >= options_.min_inliers;
  }

  index_.addFrame(words);
  frames_.push_back(std::move(stored));
  previous_words_ = std::move(words);
  recent_islands_.push_back(island);
  while (static_cast<int>(recent_islands_.size()) > options_.temporal_consistency_frames) recent_islands_.pop_front();
  purge(frame);
  return result;
}

std::vector<WordId> LoopDetector::assignWords(const Features& features, const std::vector<uint64_t>& packed) {
  const int n = static_cast<int>(features.keypoints.size());
  const int blocks = descriptorBlocks(extractor_->descriptorBytes());
  std::vector<WordId> words(n, -1);
  std::vector<bool> reinforced(n, false);
  if (!frames_.empty()) {
    const int track_bits = static_cast<int>(options_.track_distance_fraction * vocabulary_.descriptorBits());
    for (const auto& [i, j] :
         mutualMatches(features.descriptors, frames_.back().descriptors, track_bits, options_.track_ratio)) {
      if (vocabulary_.alive(previous_words_[j])) words[i] = previous_words_[j];
    }
  }
  std::vector<WordId> created;
  for (int i = 0; i < n; ++i) {
    const uint64_t* p = packed.data() + static_cast<size_t>(i) * blocks;
    if (words[i] < 0) words[i] = vocabulary_.match(p);
    if (words[i] >= 0) {
      vocabulary_.reinforce(words[i], p);
      reinforced[i] = true;
    } else {
      words[i] = vocabulary_.add(p);
      created.push_back(words[i]);
    }
  }
  // Reinforced words moved: one that now lies on another word absorbs it (the one seen more keeps its id).
  for (int i = 0; i < n; ++i) {
    const WordId w = words[i];
    if (!reinforced[i] || !vocabulary_.alive(w)) continue;
    const WordId other = vocabulary_.mergePartner(w);
    if (other < 0) continue;
    const bool keep_w = vocabulary_.observations(w) >= vocabulary_.observations(other);
    const WordId keep = keep_w ? w : other, gone = keep_w ? other : w;
    vocabulary_.merge(keep, gone);
    index_.mergeWords(keep, gone);
    std::replace(words.begin(), words.end(), gone, keep);
  }
  if (options_.purge_after_frames > 0) new_words_.emplace_back(static_cast<int64_t>(frames_.size()), std::move(created));
  return words;
}

std::optional<LoopDetector::Island> LoopDetector::bestIsland(const std::vector<WordId>& words, int64_t frame) const {
  std::vector<FrameScore> scores = index_.score(words, frame - options_.exclusion_window_frames);
  double top = 0.0;
  for (const FrameScore& s : scores) top = std::max(top, s.score);
  if (top < options_.min_similarity || top <= 0.0) return std::nullopt;
  const double floor = std::max(options_.min_similarity, options_.island_score_fraction * top);
  std::erase_if(scores, [&](const FrameScore& s) { return s.score < floor; });
  std::sort(scores.begin(), scores.end(), [](const FrameScore& a, const FrameScore& b) { return a.frame < b.frame; });
  std::optional<Island> best;
  Island current;
  auto close = [&] {
    if (!current.members.empty() && (!best || current.score > best->score)) best = current;
    current = Island{};
  };
  for (const FrameScore& s : scores) {
    if (!current.members.empty() && s.frame - current.last >= options_.island_gap_frames) close();
    if (current.members.empty()) current.first = s.frame;
    current.last = s.frame;
    current.score += s.score;
    current.members.push_back(s);
  }
  close();
  return best;
}

bool LoopDetector::temporallyConsistent(const std::optional<Island>& island) const {
  const int needed = options_.temporal_consistency_frames - 1;
  if (static_cast<int>(recent_islands_.size()) < needed) return false;
  const std::optional<Island>* later = &island;
  for (int k = 0; k < needed; ++k) {
    const std::optional<Island>& earlier = recent_islands_[recent_islands_.size() - 1 - k];
    if (!earlier) return false;
    const int64_t gap = options_.island_gap_frames;
    if (earlier->last + gap < (*later)->first || (*later)->last + gap < earlier->first) return false;
    later = &earlier;
  }
  return true;
}

void LoopDetector::purge(int64_t frame) {
  while (!new_words_.empty() && new_words_.front().first + options_.purge_after_frames <= frame) {
    for (WordId w : new_words_.front().second) {
      if (vocabulary_.alive(w) && index_.documentFrequency(w) <= 1) {
        vocabulary_.remove(w);
        index_.removeWord(w);
      }
    }
    new_words_.pop_front();
  }
}

}  // namespace rmap::loop
