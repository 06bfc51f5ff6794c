#include "loop/loop_detector.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <cmath>
#include <map>
#include <random>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>
#include <string>

#include "test_images.h"

namespace rmap::loop {
namespace {

const std::string kData = RMAP_SHARED_DATA_DIR;

/// Options for a handful of frames: no exclusion window to speak of.
LoopDetectorOptions shortSequence() {
  LoopDetectorOptions o;
  o.exclusion_window_frames = 1;
  return o;
}

TEST(LoopDetector, FindsTheDbow2DemoPairAndNoLoopBetweenUnrelatedImages) {
  const std::string dir = kData + "/loop-closure/dbow2-demo";
  if (!std::filesystem::exists(dir + "/image0.png")) GTEST_SKIP() << "shared data not found: " << dir;
  LoopDetector detector(shortSequence());
  std::vector<FrameResult> results;
  for (int i = 0; i < 4; ++i) {
    const cv::Mat img = cv::imread(dir + "/image" + std::to_string(i) + ".png", cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(img.empty());
    results.push_back(detector.addFrame(img));
    EXPECT_EQ(results.back().frame, i);
  }
  EXPECT_EQ(detector.frames(), 4u);
  EXPECT_FALSE(results[0].best);  // nothing to compare with
  EXPECT_FALSE(results[1].accepted);
  EXPECT_FALSE(results[2].accepted);
  ASSERT_TRUE(results[3].best);
  EXPECT_TRUE(results[3].accepted);
  EXPECT_EQ(results[3].best->query_frame, 3);
  EXPECT_EQ(results[3].best->reference_frame, 1);
  EXPECT_GT(results[3].best->inliers, 40);
  EXPECT_GE(results[3].best->score, detector.options().min_score);
}

TEST(LoopDetector, RevisitedSyntheticPlacesAreFoundAndNewOnesAreNot) {
  // Ten places seen twice, each visit a few frames with the camera moving; the second tour is shifted.
  LoopDetectorOptions o;
  o.exclusion_window_frames = 10;
  LoopDetector detector(o);
  std::map<int64_t, int> place_of_frame;
  std::vector<FrameResult> results;
  for (int tour = 0; tour < 2; ++tour) {
    for (int place = 0; place < 10; ++place) {
      const cv::Mat scene = test::texturedScene(100 + place);
      for (int step = 0; step < 3; ++step) {
        place_of_frame[static_cast<int64_t>(results.size())] = place;
        results.push_back(detector.addFrame(test::shifted(scene, 4.0 * step + 2.0 * tour, 1.0 * tour)));
      }
    }
  }
  int found = 0;
  for (const FrameResult& r : results) {
    if (r.frame < 30) {
      EXPECT_FALSE(r.accepted) << "frame " << r.frame << " of the first tour";
      continue;
    }
    if (!r.accepted) continue;
    ++found;
    EXPECT_EQ(place_of_frame.at(r.best->reference_frame), place_of_frame.at(r.frame)) << "frame " << r.frame;
  }
  EXPECT_GE(found, 27);
}

/// Robot "a" tours ten places; robot "b" follows one place behind, their frames interleaved:
/// each of b's frames is a place a saw a few frames ago (inside a 10-frame exclusion window).
struct FollowerTour {
  std::map<int64_t, std::pair<std::string, int>> seen;  // frame → (stream, place)
  std::vector<FrameResult> of_a, of_b;

  explicit FollowerTour(LoopDetector& detector) {
    for (int place = 0; place <= 10; ++place) {
      for (int step = 0; step < 3; ++step) {
        if (place < 10) {
          const cv::Mat image = test::shifted(test::texturedScene(100 + place), 4.0 * step, 0.0);
          of_a.push_back(detector.addFrame(PlaceImage(image), "a"));
          seen[of_a.back().frame] = {"a", place};
        }
        if (place >= 1) {
          const cv::Mat image = test::shifted(test::texturedScene(100 + place - 1), 4.0 * step + 2.0, 1.0);
          of_b.push_back(detector.addFrame(PlaceImage(image), "b"));
          seen[of_b.back().frame] = {"b", place - 1};
        }
      }
    }
  }
};

TEST(LoopDetector, InterleavedStreamsKeepTheirOwnSequenceAndCloseLoopsWithEachOther) {
  LoopDetectorOptions o;
  o.exclusion_window_frames = 10;
  o.temporal_consistency_frames = 2;  // the previous frame of b's stream must chain, not a's
  LoopDetector detector(o);
  const FollowerTour tour(detector);
  for (const FrameResult& r : tour.of_a) EXPECT_FALSE(r.accepted) << "a's frame " << r.frame << " is a new place";
  int found = 0;
  for (const FrameResult& r : tour.of_b) {
    if (!r.accepted) continue;
    ++found;
    EXPECT_EQ(tour.seen.at(r.best->reference_frame).first, "a") << "frame " << r.frame;
    EXPECT_EQ(tour.seen.at(r.best->reference_frame).second, tour.seen.at(r.frame).second) << "frame " << r.frame;
  }
  // All but b's first frame, which has no predecessor in its stream to chain with.
  EXPECT_GE(found, 27);
}

TEST(LoopDetector, AWindowOverAllStreamsKeepsOtherRobotsRecentFramesOut) {
  LoopDetectorOptions o;
  o.exclusion_window_frames = 10;
  o.exclusion_window_all_streams = true;  // as for patches cut from one shared map
  LoopDetector detector(o);
  const FollowerTour tour(detector);
  for (const FrameResult& r : tour.of_b) EXPECT_FALSE(r.accepted) << "b's frame " << r.frame;
  for (const FrameResult& r : tour.of_a) EXPECT_FALSE(r.accepted) << "a's frame " << r.frame;
}

/// A point image for a scene: pixel (u, v) shows a point of a wavy wall whose shape depends on `place`.
cv::Mat wallPoints(const cv::Size& size, int place) {
  cv::Mat points(size, CV_32FC3);
  for (int v = 0; v < size.height; ++v) {
    for (int u = 0; u < size.width; ++u) {
      const float depth = 4.0f + 1.5f * std::sin(0.03f * u + place) + 0.8f * std::cos(0.05f * v - 2.0f * place);
      points.at<cv::Vec3f>(v, u) = cv::Vec3f(depth, 0.02f * (160 - u), 0.02f * (120 - v));
    }
  }
  return points;
}

/// `points` moved by (dx, dy) pixels like test::shifted, nearest pixel.
cv::Mat shiftedPoints(const cv::Mat& points, double dx, double dy) {
  cv::Mat out;
  cv::warpAffine(points, out, cv::Matx23d(1, 0, dx, 0, 1, dy), points.size(), cv::INTER_NEAREST, cv::BORDER_REPLICATE);
  return out;
}

TEST(LoopDetector, PointImagesVerifyRevisitsInMetres) {
  LoopDetectorOptions o;
  o.exclusion_window_frames = 10;
  o.verification.model = GeometricModel::kRigid3d;
  LoopDetector detector(o);
  // Without its points a frame cannot be verified in 3D; a point image of another size is refused.
  const cv::Mat first = test::texturedScene(100);
  EXPECT_THROW(detector.addFrame(first), std::invalid_argument);
  EXPECT_THROW(detector.addFrame(PlaceImage(first, wallPoints(cv::Size(100, 100), 0))), std::invalid_argument);
  EXPECT_THROW(detector.addFrame(PlaceImage(first, cv::Mat(first.size(), CV_32FC1))), std::invalid_argument);
  EXPECT_EQ(detector.frames(), 0u);

  std::vector<FrameResult> results;
  for (int tour = 0; tour < 2; ++tour) {
    for (int place = 0; place < 10; ++place) {
      const cv::Mat scene = test::texturedScene(100 + place);
      const cv::Mat points = wallPoints(scene.size(), place);
      for (int step = 0; step < 3; ++step) {
        const double dx = 4.0 * step + 2.0 * tour, dy = 1.0 * tour;
        results.push_back(detector.addFrame(PlaceImage(test::shifted(scene, dx, dy), shiftedPoints(points, dx, dy))));
      }
    }
  }
  int found = 0;
  for (const FrameResult& r : results) {
    if (r.frame < 30) {
      EXPECT_FALSE(r.accepted) << "frame " << r.frame << " of the first tour";
      continue;
    }
    if (!r.accepted) continue;
    ++found;
    EXPECT_EQ(r.best->reference_frame / 3, (r.frame - 30) / 3) << "frame " << r.frame;
    // Each keypoint's point moved with the picture: the same points, so no motion.
    ASSERT_TRUE(r.best->reference_from_query);
    EXPECT_LT(r.best->reference_from_query->translation().norm(), 0.2) << "frame " << r.frame;
  }
  EXPECT_GE(found, 27);
}

/// 50 landmarks whose descriptors drift by 8 random bits per frame, seen over 6 frames.
std::vector<Features> driftingLandmarks() {
  std::mt19937_64 rng(9);
  std::uniform_int_distribution<int> bit(0, 255);
  cv::Mat d(50, 32, CV_8U);
  cv::randu(d, 0, 256);
  std::vector<Features> frames;
  for (int f = 0; f < 6; ++f) {
    Features features;
    for (int i = 0; i < 50; ++i) {
      features.keypoints.emplace_back(cv::Point2f(10.0f * i, 5.0f * f), 31.0f);
      for (int k = 0; k < 8; ++k) {
        const int b = bit(rng);
        d.at<uint8_t>(i, b / 8) ^= static_cast<uint8_t>(1u << (b % 8));
      }
    }
    features.descriptors = d.clone();
    frames.push_back(std::move(features));
  }
  return frames;
}

TEST(LoopDetector, TrackedFeaturesReinforceOneWordInsteadOfAddingNew) {
  // The vocabulary alone matches within 5 bits: a drift of 8 bits per frame makes a new word every
  // frame, unless the feature is tracked from the previous frame.
  LoopDetectorOptions o = shortSequence();
  o.vocabulary.match_distance_fraction = 0.02;
  o.vocabulary.merge_distance_fraction = 0.01;
  o.purge_after_frames = 0;
  LoopDetector tracking(o);
  o.track_distance_fraction = 0.01;  // 2 bits: nothing is tracked
  LoopDetector untracked(o);
  for (const Features& f : driftingLandmarks()) {
    tracking.addFeatures(f);
    untracked.addFeatures(f);
  }
  EXPECT_EQ(tracking.vocabularyWords(), 50u);
  EXPECT_GT(untracked.vocabularyWords(), 290u);  // ~one new word per landmark and frame
  for (WordId w = 0; w < static_cast<WordId>(tracking.vocabulary().capacity()); ++w) {
    if (!tracking.vocabulary().alive(w)) continue;
    EXPECT_EQ(tracking.vocabulary().observations(w), 6);
    EXPECT_EQ(tracking.index().documentFrequency(w), 6u);  // one word, in every frame
  }
}

TEST(LoopDetector, UnconfirmedWordsArePurged) {
  LoopDetectorOptions o = shortSequence();
  o.purge_after_frames = 2;
  LoopDetector detector(o);
  detector.addFrame(test::texturedScene(21));
  const size_t first = detector.vocabularyWords();
  detector.addFrame(test::texturedScene(22));  // unrelated: frame 0's words are not seen again
  detector.addFrame(test::texturedScene(23));
  EXPECT_LT(detector.vocabularyWords(), 2 * first + first / 2);  // frame 0's words went at frame 2
  o.purge_after_frames = 0;
  LoopDetector keeping(o);
  for (uint32_t s : {21u, 22u, 23u}) keeping.addFrame(test::texturedScene(s));
  EXPECT_GT(keeping.vocabularyWords(), detector.vocabularyWords());
}

TEST(LoopDetector, BadInputThrowsAndChangesNothing) {
  LoopDetector detector(shortSequence());
  detector.addFrame(test::texturedScene(1));
  const size_t words = detector.vocabularyWords();
  EXPECT_THROW(detector.addFrame(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(detector.addFrame(cv::Mat(240, 320, CV_8UC3, cv::Scalar::all(9))), std::invalid_argument);
  EXPECT_THROW(detector.addFrame(cv::Mat(16, 320, CV_8UC1, cv::Scalar::all(9))), std::invalid_argument);
  Features wrong = makeExtractor(DescriptorType::kBrisk)->extract(test::texturedScene(2));
  ASSERT_FALSE(wrong.keypoints.empty());
  EXPECT_THROW(detector.addFeatures(wrong), std::invalid_argument);  // 64-byte rows for an ORB detector
  wrong.descriptors = wrong.descriptors.colRange(0, 32).clone();
  wrong.keypoints.pop_back();
  EXPECT_THROW(detector.addFeatures(wrong), std::invalid_argument);  // rows ≠ keypoints
  Features none;
  none.descriptors = cv::Mat(3, 32, CV_8U);
  EXPECT_THROW(detector.addFeatures(none), std::invalid_argument);
  EXPECT_EQ(detector.frames(), 1u);
  EXPECT_EQ(detector.vocabularyWords(), words);
  // An image without features is a valid frame.
  const FrameResult blank = detector.addFrame(cv::Mat(64, 64, CV_8UC1, cv::Scalar::all(50)));
  EXPECT_EQ(blank.frame, 1);
  EXPECT_FALSE(blank.best);
}

TEST(LoopDetector, OptionsAreValidated) {
  EXPECT_NO_THROW(LoopDetectorOptions{}.validate());
  auto throws = [](auto change) {
    LoopDetectorOptions o;
    change(o);
    EXPECT_THROW(LoopDetector{o}, std::invalid_argument);
  };
  throws([](LoopDetectorOptions& o) { o.exclusion_window_frames = 0; });
  throws([](LoopDetectorOptions& o) { o.evidence_decay = 1.0; });
  throws([](LoopDetectorOptions& o) { o.island_score_fraction = 0.0; });
  throws([](LoopDetectorOptions& o) { o.verify_islands = 0; });
  throws([](LoopDetectorOptions& o) { o.temporal_consistency_frames = 0; });
  throws([](LoopDetectorOptions& o) { o.track_ratio = 1.5; });
  throws([](LoopDetectorOptions& o) { o.min_score = std::nan(""); });
  throws([](LoopDetectorOptions& o) { o.vocabulary.match_distance_fraction = 0.0; });
  throws([](LoopDetectorOptions& o) { o.verification.ransac_threshold_px = 0.0; });
  throws([](LoopDetectorOptions& o) { o.point_lift_radius_px = -1; });
}

/// The first 60 Lip6 frames, the 60 frames that revisit them (from 460), then 40 places not seen
/// before (from 200): loops found on the right places, none once the revisit ends.
TEST(LoopDetector, Lip6RevisitIsRecognised) {
  const std::string dir = kData + "/loop-closure/lip6-outdoor-dev";
  if (!std::filesystem::exists(dir + "/ground_truth.pairs.txt")) GTEST_SKIP() << "shared data not found: " << dir;
  std::ifstream gt_file(dir + "/ground_truth.pairs.txt");
  std::map<int, std::set<int>> truth;
  std::string line;
  while (std::getline(gt_file, line)) {
    std::istringstream in(line);
    int q = 0, r = 0;
    if (line.empty() || line[0] == '#' || !(in >> q >> r)) continue;
    truth[q].insert(r);
  }
  std::vector<int> sequence;
  for (int i = 0; i < 60; ++i) sequence.push_back(i);
  for (int i = 460; i < 520; ++i) sequence.push_back(i);
  for (int i = 200; i < 240; ++i) sequence.push_back(i);
  LoopDetector detector;
  int accepted = 0, correct = 0;
  for (size_t k = 0; k < sequence.size(); ++k) {
    char name[64];
    std::snprintf(name, sizeof name, "/images/outdoor_kennedylong_%06d.png", sequence[k]);
    const cv::Mat img = cv::imread(dir + name, cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(img.empty()) << name;
    const FrameResult r = detector.addFrame(img);
    if (!r.accepted) continue;
    ASSERT_TRUE(k >= 60 && k < 120) << "loop declared outside the revisit, frame " << sequence[k];
    ++accepted;
    const int q = sequence[k];
    const int ref = sequence[r.best->reference_frame];
    const auto& refs = truth[q];
    const bool ok = std::any_of(refs.begin(), refs.end(), [&](int t) { return std::abs(t - ref) <= 40; });
    correct += ok ? 1 : 0;
  }
  EXPECT_GE(accepted, 55);
  EXPECT_EQ(correct, accepted);
}

}  // namespace
}  // namespace rmap::loop
