#include "loop/word_tree.h"

#include <gtest/gtest.h>

#include <climits>
#include <random>

#include "loop/binary_descriptor.h"

namespace rmap::loop {
namespace {

constexpr int kBlocks = 4;  // 256 bits

/// The caller's descriptor storage (it may grow: the tree reads it through the vector).
struct Words {
  std::vector<uint64_t> storage;
  size_t add(const uint64_t* d) {
    storage.insert(storage.end(), d, d + kBlocks);
    return storage.size() / kBlocks - 1;
  }
};

std::vector<uint64_t> randomWordDescriptor(std::mt19937_64& rng) { return {rng(), rng(), rng(), rng()}; }

std::vector<uint64_t> flipped(std::vector<uint64_t> d, int flips, std::mt19937_64& rng) {
  std::uniform_int_distribution<int> bit(0, 255);
  for (int f = 0; f < flips; ++f) {
    const int b = bit(rng);
    d[b >> 6] ^= uint64_t{1} << (b & 63);
  }
  return d;
}

/// Share of noisy views (20 of 256 bits flipped) of 20,000 random words whose word is found.
double nearWordRecall(int trees) {
  Words w;
  WordTree tree(&w.storage, kBlocks, WordTreeOptions{.trees = trees});
  std::mt19937_64 rng(7);
  std::vector<std::vector<uint64_t>> queries;
  std::vector<int32_t> expected;
  for (int i = 0; i < 20000; ++i) {
    const std::vector<uint64_t> d = randomWordDescriptor(rng);
    tree.insert(static_cast<int32_t>(w.add(d.data())));
    if (i % 100 == 0) {
      queries.push_back(flipped(d, 20, rng));
      expected.push_back(i);
    }
  }
  EXPECT_EQ(tree.size(), 20000u);
  EXPECT_GE(tree.depth(), 3);
  int found = 0;
  for (size_t q = 0; q < queries.size(); ++q) {
    const NearestWords n = tree.search(queries[q].data());
    found += n.first == expected[q] ? 1 : 0;
    EXPECT_LE(n.first_distance, n.second_distance);
  }
  return static_cast<double>(found) / static_cast<double>(queries.size());
}

TEST(WordTree, FindsTheNearWordAmongManyAndMoreTreesFindMore) {
  // Uniform random words are the hard case for clustering (no structure; every word ~128 bits
  // from every other), yet most noisy views reach their word with 96 comparisons of 20,000.
  const double one = nearWordRecall(1);
  const double four = nearWordRecall(4);
  EXPECT_GT(one, 0.3);
  EXPECT_GT(four, 0.65);
  EXPECT_GT(four, one + 0.1);
}

TEST(WordTree, RemovedAndExcludedWordsAreNotReturned) {
  Words w;
  WordTree tree(&w.storage, kBlocks, WordTreeOptions{.branching = 4, .leaf_size = 8, .max_checks = 1000});
  std::mt19937_64 rng(3);
  for (int i = 0; i < 300; ++i) tree.insert(static_cast<int32_t>(w.add(randomWordDescriptor(rng).data())));
  const uint64_t* d5 = w.storage.data() + 5 * kBlocks;
  NearestWords n = tree.search(d5);
  EXPECT_EQ(n.first, 5);
  EXPECT_EQ(n.first_distance, 0);
  n = tree.search(d5, 5);
  EXPECT_NE(n.first, 5);
  EXPECT_GT(n.first_distance, 60);
  tree.remove(5);
  EXPECT_EQ(tree.size(), 299u);
  EXPECT_NE(tree.search(d5).first, 5);
  tree.remove(5);  // absent: nothing happens
  EXPECT_EQ(tree.size(), 299u);
  EXPECT_THROW(tree.insert(6), std::invalid_argument);  // already in
}

TEST(WordTree, IdenticalDescriptorsDoNotSplitForever) {
  Words w;
  WordTree tree(&w.storage, kBlocks, WordTreeOptions{.branching = 4, .leaf_size = 8});
  const uint64_t d[kBlocks] = {1, 2, 3, 4};
  for (int i = 0; i < 200; ++i) tree.insert(static_cast<int32_t>(w.add(d)));
  EXPECT_EQ(tree.size(), 200u);
  EXPECT_EQ(tree.search(d).first_distance, 0);
}

TEST(WordTree, OptionsAreValidated) {
  std::vector<uint64_t> s;
  EXPECT_THROW(WordTree(&s, kBlocks, WordTreeOptions{.branching = 1}), std::invalid_argument);
  EXPECT_THROW(WordTree(&s, kBlocks, WordTreeOptions{.branching = 16, .leaf_size = 8}), std::invalid_argument);
  EXPECT_THROW(WordTree(nullptr, kBlocks), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::loop
