#pragma once
/// @file loop_detector.h
/// Online place recognition on a stream of grey images: binary features, an
/// incremental vocabulary (no offline training), tf-idf scoring through an
/// inverted index, islands of neighbouring frames, temporal consistency and
/// geometric verification. No I/O, no threads of its own.
///
/// Per frame:
///  1. Features (the extractor, ORB by default).
///  2. Words. Descriptors matched to the previous frame's (mutual nearest,
///     ratio test, within track_distance_fraction of the bits) take the word of
///     their match: a feature tracked over consecutive frames reinforces one
///     word. The others join their nearest word within the vocabulary's match
///     distance or become new words. Reinforced words that drift onto another
///     word are merged with it. Words seen in a single frame are removed
///     purge_after_frames later (unstable detections; 0 keeps them).
///  3. Similarity s(q, f) (InvertedIndex, tf-idf) to the frames older than
///     the exclusion window (recent frames look alike without being loops).
///  4. Islands: frames scoring ≥ island_score_fraction of the best, grouped
///     when fewer than island_gap_frames apart; an island scores the sum of
///     its frames' similarities.
///  5. Geometric verification (RANSAC of the options' model: a fundamental
///     matrix, a 2D rigid motion, or a 3D rigid motion of keypoints lifted
///     to metres through a point image) of the
///     verify_per_island most similar frames of the verify_islands best
///     islands, and of the island around r + 1 when the previous frame closed
///     a loop on r (the loop continues). The frame with most inliers is the
///     candidate.
///  6. Temporal consistency, as accumulated evidence: a candidate brings
///     e = inliers − inlier_floor (the inliers a wrong place reaches), and
///     when e > 0 and its reference continues the previous frame's (within
///     island_gap_frames) it also inherits evidence_decay × the previous
///     score: score = e + evidence_decay · max(0, previous score). A loop
///     seen over consecutive frames grows surer; an isolated match must
///     stand on its own; a frame whose match is no better than a wrong
///     place's is never carried by its predecessors. With
///     temporal_consistency_frames = n > 1, a candidate is also reported
///     only when the n − 1 previous frames' candidates chain to it.
///     The loop is accepted when score ≥ min_score.
/// Streams: frames may come from several sensors moving at once (robots on
/// one map), interleaved, each frame naming its stream. The "previous frame"
/// of steps 2, 5 and 6, the islands of step 4 and the exclusion window of
/// step 3 follow each stream's own order, so interleaved robots never track,
/// chain or group each other's frames. The vocabulary and the index are
/// shared: a frame may close a loop with any other stream's frame, a recent
/// one included (two robots at one place at once). One stream behaves as a
/// detector without streams.
/// Memory per frame: keypoint positions and descriptors (≈ (8 + descriptor
/// bytes) × features, 20 KB for 500 ORB features; kRigid3d 12 bytes more a
/// keypoint), plus the vocabulary (≈ 50 words per frame kept on Lip6).
/// Windows are in frames of a stream: feed frames at a steady pace of motion
/// (a robot standing still for longer than the exclusion window would close
/// loops on itself). Thread-compatible, not thread-safe.

#include <Eigen/Geometry>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "loop/binary_features.h"
#include "loop/geometric_verification.h"
#include "loop/incremental_vocabulary.h"
#include "loop/inverted_index.h"
#include "loop/point_image.h"

namespace rmap::loop {

struct LoopDetectorOptions {
  VocabularyOptions vocabulary;
  GeometricVerificationOptions verification;
  double track_distance_fraction = 0.2;  ///< tracked descriptor pairs within this fraction of the bits ...
  double track_ratio = 0.8;              ///< ... and below this nearest / second-nearest ratio
  int purge_after_frames = 2;            ///< words seen in one frame only are dropped this many frames later (0: never)
  int exclusion_window_frames = 50;      ///< the most recent frames of the frame's own stream are not loop candidates
  /// Also every other stream's frames taken since the stream's frame exclusion_window_frames
  /// back: for frames that are not independent views (patches cut from one shared map show
  /// what the other robot just drew).
  bool exclusion_window_all_streams = false;
  double min_similarity = 0.0;           ///< frames less similar than this are not candidates
  double island_score_fraction = 0.5;    ///< candidates score at least this fraction of the best frame
  int island_gap_frames = 5;             ///< candidates of one stream this close (frames of the stream) form one island
  int temporal_consistency_frames = 1;   ///< consecutive frames whose candidates must chain (1: evidence only)
  int verify_islands = 2;                ///< highest-scoring islands verified geometrically ...
  int verify_per_island = 2;             ///< ... through their most similar frames
  double inlier_floor = 10.0;            ///< inliers that bring no evidence (what wrong places reach)
  double evidence_decay = 0.75;          ///< share of the previous frame's score a continuing loop inherits, [0, 1)
  double min_score = 10.0;               ///< acceptance threshold on the score
  /// addFrame with a point image: a keypoint takes the point of the nearest pixel
  /// that has one within this many pixels (a panorama's fill_iterations: its filled
  /// pixels are that close to a real one), else it is dropped. ≥ 0.
  int point_lift_radius_px = 4;
  /// @throws std::invalid_argument naming the first bad field
  void validate() const;
};

/// The options for laser-intensity panoramas of 3D clouds (rmapd's, and the benchmarks'):
/// the defaults, verified in metres (kRigid3d; each frame needs its point image) and
/// accepted only when the stream's previous frame's candidate chains to the same place
/// (temporal_consistency_frames 2): a building's storeys can repeat a corridor end with its
/// walls at the same ranges and the same intensities, a look-alike no single frame tells
/// apart, while a true revisit goes on over the next frames (BENCHMARKS.md §7).
LoopDetectorOptions panoramaDetectorOptions();

struct LoopCandidate {
  int64_t query_frame = -1;      ///< 0-based index of the frame just added
  int64_t reference_frame = -1;  ///< 0-based index of the older frame it matches
  double score = 0.0;            ///< the acceptance score swept for precision–recall curves (higher = surer; see step 6)
  int inliers = 0;               ///< geometric verification inliers
  int matches = 0;               ///< putative descriptor matches the inliers were drawn from
  double similarity = 0.0;       ///< tf-idf similarity of the two frames (InvertedIndex), 0..1
  /// kRigid3d: the fitted motion, reference sensor frame from query sensor frame (metres).
  std::optional<Eigen::Isometry3d> reference_from_query;
  /// kRigid2d: the fitted motion of the pixels, query image onto reference image (Verification).
  std::optional<Eigen::Isometry2d> reference_from_query_px;
};

struct FrameResult {
  int64_t frame = -1;
  /// Best verified candidate that passed every test but the acceptance threshold (for sweeps).
  std::optional<LoopCandidate> best;
  bool accepted = false;  ///< best passed every test at the configured threshold
};

class LoopDetector {
 public:
  /// @param extractor  nullptr = ORB with the default options
  /// @throws std::invalid_argument for invalid options
  explicit LoopDetector(LoopDetectorOptions options = {}, std::unique_ptr<FeatureExtractor> extractor = nullptr);

  /// Adds the next frame (8-bit grey, ≥ 32×32 px) of the unnamed stream and looks for a loop among older frames.
  /// @throws std::invalid_argument for an empty / wrong-type / too small image; state unchanged
  /// @throws std::invalid_argument when the verification model is kRigid3d (it needs a point image)
  FrameResult addFrame(const cv::Mat& gray);
  /// Same for a frame of `stream`. With a point image (point_image.h: CV_32FC3, the image's
  /// size), keypoints without a point near them are dropped and kRigid3d verifies on the rest.
  /// @throws std::invalid_argument for a bad image or point image, or kRigid3d without one; state unchanged
  FrameResult addFrame(const PlaceImage& image, const std::string& stream = {});
  /// Same with features the caller extracted (same descriptor type as the extractor),
  /// and for kRigid3d each keypoint's point (metres, sensor frame).
  /// @throws std::invalid_argument when descriptors are not CV_8U rows of the extractor's width, one per keypoint,
  ///         or kRigid3d is not given one finite point per keypoint
  FrameResult addFeatures(const Features& features, std::vector<Eigen::Vector3f> points_m = {},
                          const std::string& stream = {});

  size_t frames() const { return frames_.size(); }
  size_t vocabularyWords() const { return vocabulary_.size(); }
  const LoopDetectorOptions& options() const { return options_; }
  const IncrementalVocabulary& vocabulary() const { return vocabulary_; }
  const InvertedIndex& index() const { return index_; }

 private:
  struct StoredFrame {
    std::vector<cv::Point2f> points;
    std::vector<Eigen::Vector3f> points_m;  ///< kRigid3d: each keypoint's point
    cv::Mat descriptors;
    size_t stream = 0;    ///< index into streams_
    int64_t ordinal = 0;  ///< its place in its stream (0, 1, ...)
  };
  /// What follows one stream's order.
  struct Stream {
    std::vector<int64_t> frames;          ///< its frames (indices into frames_), oldest first
    std::vector<WordId> previous_words;   ///< word of each feature of its previous frame
    std::deque<std::optional<LoopCandidate>> recent;  ///< best candidates of its last frames, newest last
    std::deque<std::pair<int64_t, std::vector<WordId>>> new_words;  ///< (ordinal, words it created), awaiting purge
  };
  struct Island {
    size_t stream = 0;
    int64_t first = -1, last = -1;  ///< ordinals in that stream
    double score = 0.0;
    std::vector<FrameScore> members;
  };

  std::vector<WordId> assignWords(const Features& features, const std::vector<uint64_t>& packed, Stream& stream);
  /// Islands of the frames scoring near the best, highest island score first.
  std::vector<Island> islands(std::vector<FrameScore> scores) const;
  /// The frames around the successor of the stream's previous accepted reference, if it had one.
  /// @param own_frames    frames of the new frame's stream before it
  /// @param window_start  exclusion_window_all_streams: frames from this index on are excluded
  std::optional<Island> predictedIsland(const std::vector<FrameScore>& scores, size_t stream_id, int64_t own_frames,
                                        int64_t window_start) const;
  /// Whether `reference` continues the loop of an earlier frame's candidate.
  bool continues(const LoopCandidate& earlier, int64_t reference) const;
  /// Whether the stream's previous temporal_consistency_frames − 1 frames had candidates chaining to `reference`.
  bool temporallyConsistent(const Stream& stream, int64_t reference) const;
  /// Drops the stream's words that no frame confirmed purge_after_frames of its frames later.
  void purge(Stream& stream, int64_t ordinal);
  size_t streamId(const std::string& name);

  LoopDetectorOptions options_;
  std::unique_ptr<FeatureExtractor> extractor_;
  IncrementalVocabulary vocabulary_;
  InvertedIndex index_;
  std::vector<StoredFrame> frames_;
  std::vector<Stream> streams_;
  std::unordered_map<std::string, size_t> stream_ids_;
};

}  // namespace rmap::loop
