#pragma once
/// @file incremental_vocabulary.h
/// A vocabulary of binary words grown online, with no offline training.
///
/// A word is the bitwise majority of the descriptors it has absorbed: each
/// word keeps, per bit, how many of its descriptors had the bit set, and its
/// descriptor is bit b = (ones_b > observations / 2), a tie keeping the old
/// bit. A descriptor close to an existing word (Hamming distance within
/// match_distance_fraction of the descriptor bits) reinforces it; otherwise
/// it becomes a new word. Two words that drift within merge_distance_fraction
/// of each other are merged (their counts add). Counts are 16-bit and halved
/// when a word reaches max_observations, so a word follows slow changes of
/// appearance instead of freezing.
///
/// Nearest-word search goes through a WordTree (approximate, cost flat in
/// the vocabulary size). Word ids are stable; removed or merged-away ids are
/// not reused. Memory: descriptor bytes per word, plus 2 bytes per bit for
/// words seen more than once. Not thread-safe, searches included (the tree
/// keeps scratch marks).

#include <cstdint>
#include <vector>

#include "loop/word_tree.h"

namespace rmap::loop {

using WordId = int32_t;

struct VocabularyOptions {
  double match_distance_fraction = 0.2;   ///< a descriptor joins its nearest word within this fraction of bits
  double merge_distance_fraction = 0.1;   ///< words within this fraction of bits of each other are merged
  int max_observations = 4096;            ///< counts are halved when a word reaches this many observations
  WordTreeOptions tree;
  /// @throws std::invalid_argument naming the first bad field
  void validate() const;
};

class IncrementalVocabulary {
 public:
  /// @param descriptor_bytes  bytes per descriptor (32 ORB, 64 BRISK, 61 AKAZE)
  explicit IncrementalVocabulary(int descriptor_bytes, VocabularyOptions options = {});

  int descriptorBytes() const { return bytes_; }
  int descriptorBits() const { return bytes_ * 8; }
  int matchDistanceBits() const { return match_bits_; }
  int mergeDistanceBits() const { return merge_bits_; }

  /// The nearest word within the match distance of a packed descriptor, or -1.
  WordId match(const uint64_t* descriptor) const;
  /// The nearest other word within the merge distance of `word`'s descriptor, or -1.
  WordId mergePartner(WordId word) const;

  /// A new word holding one packed descriptor.
  WordId add(const uint64_t* descriptor);
  /// Adds a packed descriptor's bits to `word`'s counts and updates its majority descriptor.
  /// @return whether the word's descriptor changed
  bool reinforce(WordId word, const uint64_t* descriptor);
  /// Moves `gone`'s counts into `keep`; `gone` stops existing.
  void merge(WordId keep, WordId gone);
  void remove(WordId word);

  bool alive(WordId word) const { return word >= 0 && static_cast<size_t>(word) < observations_.size() && observations_[word] > 0; }
  /// Descriptors absorbed (after halving); 0 for a removed word.
  int observations(WordId word) const { return observations_[word]; }
  const uint64_t* descriptor(WordId word) const { return descriptors_.data() + static_cast<size_t>(word) * blocks_; }
  /// Live words.
  size_t size() const { return live_; }
  /// Ids handed out so far (live or not): valid ids are [0, capacity()).
  size_t capacity() const { return observations_.size(); }

 private:
  std::vector<uint16_t>& counts(WordId word);  ///< per-bit ones, materialised on the second observation
  bool recomputeDescriptor(WordId word);  ///< @return whether a bit changed

  int bytes_;
  int blocks_;
  VocabularyOptions options_;
  int match_bits_;
  int merge_bits_;
  std::vector<uint64_t> descriptors_;
  std::vector<int> observations_;
  std::vector<std::vector<uint16_t>> ones_;
  size_t live_ = 0;
  WordTree tree_;
};

}  // namespace rmap::loop
