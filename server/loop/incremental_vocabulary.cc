#include "loop/incremental_vocabulary.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "loop/binary_descriptor.h"

namespace rmap::loop {

void VocabularyOptions::validate() const {
  auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("VocabularyOptions: ") + what);
  };
  require(match_distance_fraction > 0.0 && match_distance_fraction < 0.5, "match_distance_fraction must be in (0, 0.5)");
  require(merge_distance_fraction >= 0.0 && merge_distance_fraction <= match_distance_fraction,
          "merge_distance_fraction must be in [0, match_distance_fraction]");
  require(max_observations >= 2 && max_observations <= 16384, "max_observations must be in [2, 16384]");
  tree.validate();
}

IncrementalVocabulary::IncrementalVocabulary(int descriptor_bytes, VocabularyOptions options)
    : bytes_(descriptor_bytes),
      blocks_(descriptorBlocks(descriptor_bytes)),
      options_((options.validate(), options)),
      match_bits_(static_cast<int>(std::floor(options.match_distance_fraction * descriptor_bytes * 8))),
      merge_bits_(static_cast<int>(std::floor(options.merge_distance_fraction * descriptor_bytes * 8))),
      tree_(&descriptors_, descriptorBlocks(descriptor_bytes), options.tree) {
  if (descriptor_bytes < 1 || descriptor_bytes > 1024) {
    throw std::invalid_argument("IncrementalVocabulary: descriptor_bytes must be in [1, 1024]");
  }
}

WordId IncrementalVocabulary::match(const uint64_t* descriptor) const {
  const NearestWords n = tree_.search(descriptor);
  return n.first >= 0 && n.first_distance <= match_bits_ ? n.first : -1;
}

WordId IncrementalVocabulary::mergePartner(WordId word) const {
  const NearestWords n = tree_.search(descriptor(word), word);
  return n.first >= 0 && n.first_distance <= merge_bits_ ? n.first : -1;
}

WordId IncrementalVocabulary::add(const uint64_t* d) {
  const auto id = static_cast<WordId>(observations_.size());
  descriptors_.insert(descriptors_.end(), d, d + blocks_);
  observations_.push_back(1);
  ones_.emplace_back();
  ++live_;
  tree_.insert(id);
  return id;
}

std::vector<uint16_t>& IncrementalVocabulary::counts(WordId word) {
  std::vector<uint16_t>& c = ones_[word];
  if (c.empty()) {  // one observation so far: its counts are its bits
    c.resize(static_cast<size_t>(descriptorBits()));
    const uint64_t* d = descriptor(word);
    for (int b = 0; b < descriptorBits(); ++b) c[b] = testBit(d, b) ? observations_[word] : 0;
  }
  return c;
}

bool IncrementalVocabulary::recomputeDescriptor(WordId word) {
  const std::vector<uint16_t>& c = ones_[word];
  uint64_t* d = descriptors_.data() + static_cast<size_t>(word) * blocks_;
  const std::vector<uint64_t> before(d, d + blocks_);
  const int n = observations_[word];
  for (int b = 0; b < descriptorBits(); ++b) {
    const int twice = 2 * c[b];
    if (twice == n) continue;  // a tie keeps the current bit
    const uint64_t mask = uint64_t{1} << (b & 63);
    if (twice > n) d[b >> 6] |= mask;
    else d[b >> 6] &= ~mask;
  }
  if (n >= options_.max_observations) {  // halve: the word keeps following its descriptors
    std::vector<uint16_t>& cm = ones_[word];
    for (uint16_t& v : cm) v = static_cast<uint16_t>((v + 1) / 2);
    observations_[word] = (n + 1) / 2;
  }
  return !std::equal(before.begin(), before.end(), d);
}

bool IncrementalVocabulary::reinforce(WordId word, const uint64_t* d) {
  if (!alive(word)) throw std::invalid_argument("IncrementalVocabulary::reinforce: no word " + std::to_string(word));
  std::vector<uint16_t>& c = counts(word);
  for (int b = 0; b < descriptorBits(); ++b) c[b] = static_cast<uint16_t>(c[b] + (testBit(d, b) ? 1 : 0));
  ++observations_[word];
  return recomputeDescriptor(word);
}

void IncrementalVocabulary::merge(WordId keep, WordId gone) {
  if (!alive(keep) || !alive(gone) || keep == gone) {
    throw std::invalid_argument("IncrementalVocabulary::merge: needs two distinct live words");
  }
  std::vector<uint16_t>& ck = counts(keep);
  const std::vector<uint16_t>& cg = counts(gone);
  for (int b = 0; b < descriptorBits(); ++b) ck[b] = static_cast<uint16_t>(ck[b] + cg[b]);
  observations_[keep] += observations_[gone];
  remove(gone);
  recomputeDescriptor(keep);
}

void IncrementalVocabulary::remove(WordId word) {
  if (!alive(word)) return;
  tree_.remove(word);
  observations_[word] = 0;
  ones_[word] = {};
  --live_;
}

}  // namespace rmap::loop
