#pragma once
/// @file inverted_index.h
/// Word → frames inverted index with tf-idf similarity.
///
/// A frame is the multiset of the words of its features. With n_f the
/// frame's feature count, tf_f(w) = count_f(w) / n_f, and, counting the query
/// as one more document, idf(w) = ln((N + 1) / (df(w) + 1)) with N indexed
/// frames and df(w) the frames holding w. The similarity of query q to frame f
///     s(q, f) = Σ_w idf(w) · min(tf_q(w), tf_f(w)) / Σ_w idf(w) · tf_q(w)
/// is the idf-weighted histogram intersection normalised by the query, in
/// [0, 1] (1: f holds all of q's words at least as often). idf is the
/// current one, so the scores of old frames stay comparable as the
/// vocabulary grows. Scoring costs Σ_{w ∈ q} df(w).

#include <cstdint>
#include <span>
#include <vector>

#include "loop/incremental_vocabulary.h"

namespace rmap::loop {

struct FrameScore {
  int64_t frame = -1;
  double score = 0.0;
};

class InvertedIndex {
 public:
  /// Appends the next frame (id frames()) holding `words` (one per feature, repeats allowed, -1 skipped).
  void addFrame(std::span<const WordId> words);
  /// Postings of `gone` move to `keep` (counts add where both were in a frame).
  void mergeWords(WordId keep, WordId gone);
  void removeWord(WordId word);

  /// s(q, f) for every frame f < before_frame sharing a word with the query, unsorted.
  std::vector<FrameScore> score(std::span<const WordId> query_words, int64_t before_frame) const;

  size_t frames() const { return frame_features_.size(); }
  /// Frames holding `word`.
  size_t documentFrequency(WordId word) const;
  /// Times `word` occurs in `frame` (0 if not).
  int count(WordId word, int64_t frame) const;

 private:
  struct Posting {
    int32_t frame;
    uint16_t count;
  };
  std::vector<std::vector<Posting>> postings_;  ///< by word id, sorted by frame
  std::vector<uint32_t> frame_features_;        ///< n_f
  mutable std::vector<double> accumulator_;     ///< by frame, zero between calls
};

}  // namespace rmap::loop
