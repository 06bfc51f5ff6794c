#include "loop/incremental_vocabulary.h"

#include <gtest/gtest.h>

#include <random>

#include "loop/binary_descriptor.h"

namespace rmap::loop {
namespace {

using Descriptor = std::array<uint64_t, 4>;  // 32 bytes, ORB-sized

Descriptor randomDescriptor(std::mt19937_64& rng) { return {rng(), rng(), rng(), rng()}; }

Descriptor withFlips(Descriptor d, std::initializer_list<int> bits) {
  for (int b : bits) d[b >> 6] ^= uint64_t{1} << (b & 63);
  return d;
}

int distance(const uint64_t* a, const Descriptor& b) { return hammingDistance(a, b.data(), 4); }

TEST(IncrementalVocabulary, CloseDescriptorsMatchAndFarOnesBecomeNewWords) {
  IncrementalVocabulary v(32);
  EXPECT_EQ(v.matchDistanceBits(), 51);  // 0.2 · 256
  std::mt19937_64 rng(1);
  const Descriptor a = randomDescriptor(rng);
  EXPECT_EQ(v.match(a.data()), -1);  // empty vocabulary
  const WordId wa = v.add(a.data());
  EXPECT_EQ(v.size(), 1u);
  EXPECT_EQ(v.match(withFlips(a, {1, 70, 150, 200}).data()), wa);
  EXPECT_EQ(v.match(randomDescriptor(rng).data()), -1);  // ~128 bits away
  const WordId wb = v.add(randomDescriptor(rng).data());
  EXPECT_NE(wb, wa);
  EXPECT_EQ(v.size(), 2u);
}

TEST(IncrementalVocabulary, ReinforcedWordsTakeTheBitwiseMajority) {
  IncrementalVocabulary v(32);
  std::mt19937_64 rng(2);
  const Descriptor base = randomDescriptor(rng);
  const WordId w = v.add(withFlips(base, {3}).data());  // bit 3 flipped in one observation of three
  v.reinforce(w, withFlips(base, {100}).data());
  // Two observations: bits 3 and 100 are 1-1 ties, which keep the first descriptor's value.
  EXPECT_EQ(distance(v.descriptor(w), withFlips(base, {3})), 0);
  v.reinforce(w, base.data());
  EXPECT_EQ(v.observations(w), 3);
  EXPECT_EQ(distance(v.descriptor(w), base), 0);  // each flip is outvoted 2 to 1
  EXPECT_THROW(v.reinforce(99, base.data()), std::invalid_argument);
}

TEST(IncrementalVocabulary, DriftedWordsMergeAndTheirCountsAdd) {
  IncrementalVocabulary v(32);
  EXPECT_EQ(v.mergeDistanceBits(), 25);  // 0.1 · 256
  std::mt19937_64 rng(3);
  const Descriptor base = randomDescriptor(rng);
  const WordId a = v.add(base.data());
  v.reinforce(a, base.data());
  const WordId b = v.add(withFlips(base, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10}).data());
  const WordId far = v.add(randomDescriptor(rng).data());
  EXPECT_EQ(v.mergePartner(a), b);
  EXPECT_EQ(v.mergePartner(far), -1);
  v.merge(a, b);
  EXPECT_FALSE(v.alive(b));
  EXPECT_TRUE(v.alive(a));
  EXPECT_EQ(v.observations(a), 3);
  EXPECT_EQ(v.size(), 2u);
  EXPECT_EQ(distance(v.descriptor(a), base), 0);  // 2 against 1 on each flipped bit
  EXPECT_EQ(v.match(base.data()), a);            // b is gone from the search too
  EXPECT_THROW(v.merge(a, b), std::invalid_argument);
  EXPECT_THROW(v.merge(a, a), std::invalid_argument);
  v.remove(far);
  EXPECT_EQ(v.size(), 1u);
  EXPECT_EQ(v.capacity(), 3u);  // ids are not reused
}

TEST(IncrementalVocabulary, CountsHalveAtTheCapAndKeepFollowingTheDescriptors) {
  VocabularyOptions o;
  o.max_observations = 8;
  IncrementalVocabulary v(32, o);
  std::mt19937_64 rng(4);
  const Descriptor old_look = randomDescriptor(rng);
  const Descriptor new_look = withFlips(old_look, {0, 1, 2, 3, 4, 5});
  const WordId w = v.add(old_look.data());
  for (int i = 0; i < 7; ++i) v.reinforce(w, old_look.data());
  EXPECT_LE(v.observations(w), 8);
  for (int i = 0; i < 6; ++i) v.reinforce(w, new_look.data());
  EXPECT_EQ(distance(v.descriptor(w), new_look), 0);  // halving let the new look win within 6 observations
}

TEST(IncrementalVocabulary, OptionsAreValidated) {
  VocabularyOptions o;
  o.match_distance_fraction = 0.6;
  EXPECT_THROW(IncrementalVocabulary(32, o), std::invalid_argument);
  o = {};
  o.merge_distance_fraction = 0.3;  // above the match distance
  EXPECT_THROW(o.validate(), std::invalid_argument);
  o = {};
  o.max_observations = 1;
  EXPECT_THROW(o.validate(), std::invalid_argument);
  EXPECT_THROW(IncrementalVocabulary(0), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::loop
