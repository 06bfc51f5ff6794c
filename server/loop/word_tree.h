#pragma once
/// @file word_tree.h
/// Approximate nearest-word search in Hamming space that stays fast as the
/// vocabulary grows: a forest of hierarchical clustering trees built
/// incrementally (each tree indexes every word; their random centres differ,
/// so a query near a cluster border in one tree is inside a cluster in
/// another).
///
/// Leaves hold word ids. A word is inserted by descending to the nearest
/// centre at each level; a leaf that outgrows leaf_size is split in place
/// into `branching` children around centres seeded k-means++-style among its
/// words and refined by a few k-medians iterations (a centre is the bitwise
/// majority of its words), so the tree is rebuilt locally, never globally. Search is best-bin-first: descend to the
/// nearest leaf, keep the unexplored siblings in a priority queue ordered by
/// their centre distance, and stop after `max_checks` word comparisons.
/// Cost per search: O(branching · depth + max_checks) Hamming distances,
/// depth ≈ log_branching(words / leaf_size).
///
/// Word descriptors live in the caller's storage (`descriptors`, `blocks`
/// 64-bit blocks per word id); a word whose descriptor changes stays where
/// it was inserted (it drifts by a few bits at most).

#include <cstdint>
#include <random>
#include <vector>

namespace rmap::loop {

struct WordTreeOptions {
  int branching = 16;   ///< children of a split leaf
  int leaf_size = 64;   ///< words a leaf holds before it splits
  int trees = 4;        ///< independent trees over the same words
  int max_checks = 96;  ///< distinct words compared per search, over all trees (leaves are finished once started)
  int refinements = 3;  ///< k-medians iterations after the k-means++ seeding of a split
  uint64_t seed = 1;    ///< centre picking (the forest is deterministic for a given insertion order)
  /// @throws std::invalid_argument naming the first bad field
  void validate() const;
};

/// The two nearest words found (id -1 and distance INT_MAX when absent).
struct NearestWords {
  int32_t first = -1;
  int first_distance = 0;
  int32_t second = -1;
  int second_distance = 0;
};

class WordTree {
 public:
  /// @param descriptors  packed word descriptors indexed by word id (`blocks` per word), owned by the caller
  WordTree(const std::vector<uint64_t>* descriptors, int blocks, WordTreeOptions options = {});

  void insert(int32_t word);
  void remove(int32_t word);
  /// Nearest words to `query` (packed), skipping `exclude` (-1: none). Not thread-safe (scratch marks).
  NearestWords search(const uint64_t* query, int32_t exclude = -1) const;

  size_t size() const { return words_; }
  /// Levels from the root to the deepest leaf of the first tree (1 = the root is a leaf).
  int depth() const;

 private:
  struct Node {
    std::vector<uint64_t> centres;  ///< internal: one packed centre per child
    std::vector<int32_t> children;  ///< internal: node index per child; empty for a leaf
    std::vector<int32_t> words;     ///< leaf: word ids
  };

  struct Tree {
    std::vector<Node> nodes{1};
    std::vector<int32_t> leaf_of;  ///< word id → leaf node (-1: not in the tree)
    std::mt19937_64 rng;
  };

  const uint64_t* descriptorOf(int32_t word) const;
  int32_t nearestChild(const Node& node, const uint64_t* d) const;
  void insert(Tree& tree, int32_t word);
  void split(Tree& tree, int32_t node);
  int depthBelow(const Tree& tree, int32_t node) const;

  const std::vector<uint64_t>* descriptors_;
  int blocks_;
  WordTreeOptions options_;
  std::vector<Tree> trees_;
  size_t words_ = 0;
  struct Branch {  ///< an unexplored node of a search, by its centre's distance to the query
    int distance;
    int32_t tree, node;
    bool operator>(const Branch& o) const { return distance > o.distance; }
  };
  mutable std::vector<Branch> queue_;      ///< search scratch: the best-bin-first heap
  mutable std::vector<uint32_t> checked_;  ///< word id → search stamp of its last comparison
  mutable uint32_t stamp_ = 0;
};

}  // namespace rmap::loop
