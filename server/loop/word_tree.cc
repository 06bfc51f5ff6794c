#include "loop/word_tree.h"

#include <algorithm>
#include <climits>
#include <functional>
#include <stdexcept>
#include <string>

#include "loop/binary_descriptor.h"

namespace rmap::loop {

void WordTreeOptions::validate() const {
  auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("WordTreeOptions: ") + what);
  };
  require(branching >= 2 && branching <= 256, "branching must be in [2, 256]");
  require(leaf_size >= branching, "leaf_size must be >= branching");
  require(trees >= 1 && trees <= 16, "trees must be in [1, 16]");
  require(max_checks >= 1, "max_checks must be >= 1");
  require(refinements >= 0, "refinements must be >= 0");
}

WordTree::WordTree(const std::vector<uint64_t>* descriptors, int blocks, WordTreeOptions options)
    : descriptors_(descriptors), blocks_(blocks), options_(options) {
  options_.validate();
  if (descriptors_ == nullptr || blocks_ < 1) throw std::invalid_argument("WordTree: no descriptor storage");
  trees_.resize(static_cast<size_t>(options_.trees));
  for (size_t t = 0; t < trees_.size(); ++t) trees_[t].rng.seed(options_.seed + 7919 * t);
}

const uint64_t* WordTree::descriptorOf(int32_t word) const {
  return descriptors_->data() + static_cast<size_t>(word) * blocks_;
}

int32_t WordTree::nearestChild(const Node& node, const uint64_t* d) const {
  int best = 0, best_d = INT_MAX;
  for (size_t c = 0; c < node.children.size(); ++c) {
    const int dc = hammingDistance(d, node.centres.data() + c * blocks_, blocks_);
    if (dc < best_d) best_d = dc, best = static_cast<int>(c);
  }
  return node.children[best];
}

void WordTree::insert(int32_t word) {
  if (word < 0) throw std::invalid_argument("WordTree::insert: negative word id");
  if (static_cast<size_t>(word) < trees_[0].leaf_of.size() && trees_[0].leaf_of[word] >= 0) {
    throw std::invalid_argument("WordTree::insert: word already in the tree");
  }
  for (Tree& tree : trees_) insert(tree, word);
  if (static_cast<size_t>(word) >= checked_.size()) checked_.resize(static_cast<size_t>(word) + 1, 0);
  ++words_;
}

void WordTree::insert(Tree& tree, int32_t word) {
  if (static_cast<size_t>(word) >= tree.leaf_of.size()) tree.leaf_of.resize(static_cast<size_t>(word) + 1, -1);
  int32_t leaf = 0;
  while (!tree.nodes[leaf].children.empty()) leaf = nearestChild(tree.nodes[leaf], descriptorOf(word));
  tree.nodes[leaf].words.push_back(word);
  tree.leaf_of[word] = leaf;
  if (static_cast<int>(tree.nodes[leaf].words.size()) > options_.leaf_size) split(tree, leaf);
}

void WordTree::remove(int32_t word) {
  if (word < 0 || static_cast<size_t>(word) >= trees_[0].leaf_of.size() || trees_[0].leaf_of[word] < 0) return;
  for (Tree& tree : trees_) {
    std::vector<int32_t>& ws = tree.nodes[tree.leaf_of[word]].words;
    auto it = std::find(ws.begin(), ws.end(), word);
    *it = ws.back();
    ws.pop_back();
    tree.leaf_of[word] = -1;
  }
  --words_;
}

void WordTree::split(Tree& tree, int32_t node) {
  std::vector<int32_t> words = std::move(tree.nodes[node].words);
  tree.nodes[node].words.clear();
  // k-means++ seeding: each next centre drawn with probability ∝ squared distance to the chosen ones.
  const int k = options_.branching;
  std::vector<int> nearest(words.size(), INT_MAX);
  std::vector<int32_t> centre_words;
  centre_words.push_back(words[std::uniform_int_distribution<size_t>(0, words.size() - 1)(tree.rng)]);
  while (static_cast<int>(centre_words.size()) < k) {
    double total = 0.0;
    for (size_t i = 0; i < words.size(); ++i) {
      const int d = hammingDistance(descriptorOf(words[i]), descriptorOf(centre_words.back()), blocks_);
      nearest[i] = std::min(nearest[i], d);
      total += static_cast<double>(nearest[i]) * nearest[i];
    }
    if (total == 0.0) break;  // the remaining words duplicate the centres
    double pick = std::uniform_real_distribution<double>(0.0, total)(tree.rng);
    size_t chosen = words.size() - 1;
    for (size_t i = 0; i < words.size(); ++i) {
      pick -= static_cast<double>(nearest[i]) * nearest[i];
      if (pick <= 0.0 && nearest[i] > 0) {
        chosen = i;
        break;
      }
    }
    centre_words.push_back(words[chosen]);
  }
  if (centre_words.size() < 2) {  // identical descriptors: nothing to split on
    tree.nodes[node].words = std::move(words);
    return;
  }
  const size_t k_used = centre_words.size();
  std::vector<uint64_t> centres(k_used * blocks_);
  for (size_t c = 0; c < k_used; ++c) std::copy_n(descriptorOf(centre_words[c]), blocks_, centres.begin() + c * blocks_);
  std::vector<int> cluster(words.size());
  auto assign = [&] {
    for (size_t i = 0; i < words.size(); ++i) {
      int best = 0, best_d = INT_MAX;
      for (size_t c = 0; c < k_used; ++c) {
        const int d = hammingDistance(descriptorOf(words[i]), centres.data() + c * blocks_, blocks_);
        if (d < best_d) best_d = d, best = static_cast<int>(c);
      }
      cluster[i] = best;
    }
  };
  // k-medians in Hamming space: a centre becomes the bitwise majority of its words.
  const int bits = blocks_ * 64;
  std::vector<int> ones(k_used * bits), members(k_used);
  for (int iteration = 0; iteration < options_.refinements; ++iteration) {
    assign();
    std::fill(ones.begin(), ones.end(), 0);
    std::fill(members.begin(), members.end(), 0);
    for (size_t i = 0; i < words.size(); ++i) {
      const uint64_t* d = descriptorOf(words[i]);
      ++members[cluster[i]];
      for (int b = 0; b < bits; ++b) ones[cluster[i] * bits + b] += testBit(d, b) ? 1 : 0;
    }
    for (size_t c = 0; c < k_used; ++c) {
      if (members[c] == 0) continue;
      uint64_t* centre = centres.data() + c * blocks_;
      for (int b = 0; b < bits; ++b) {
        const uint64_t mask = uint64_t{1} << (b & 63);
        if (2 * ones[c * bits + b] > members[c]) centre[b >> 6] |= mask;
        else if (2 * ones[c * bits + b] < members[c]) centre[b >> 6] &= ~mask;
      }
    }
  }
  assign();
  std::vector<int32_t> children;
  for (size_t c = 0; c < k_used; ++c) {
    children.push_back(static_cast<int32_t>(tree.nodes.size()));
    tree.nodes.emplace_back();
  }
  for (size_t i = 0; i < words.size(); ++i) {
    tree.nodes[children[cluster[i]]].words.push_back(words[i]);
    tree.leaf_of[words[i]] = children[cluster[i]];
  }
  tree.nodes[node].centres = std::move(centres);
  tree.nodes[node].children = std::move(children);
}

NearestWords WordTree::search(const uint64_t* query, int32_t exclude) const {
  NearestWords out;
  out.first_distance = out.second_distance = INT_MAX;
  if (++stamp_ == 0) {  // wrapped: forget every mark
    std::fill(checked_.begin(), checked_.end(), 0);
    stamp_ = 1;
  }
  // A binary min-heap on the reused scratch vector (the operations of
  // std::priority_queue, without its allocation per search).
  std::vector<Branch>& queue = queue_;
  queue.clear();
  const auto push = [&](Branch b) {
    queue.push_back(b);
    std::push_heap(queue.begin(), queue.end(), std::greater<>());
  };
  for (size_t t = 0; t < trees_.size(); ++t) push({0, static_cast<int32_t>(t), 0});
  int checks = 0;
  while (!queue.empty() && checks < options_.max_checks) {
    const Tree& tree = trees_[queue.front().tree];
    const int32_t t = queue.front().tree;
    int32_t n = queue.front().node;
    std::pop_heap(queue.begin(), queue.end(), std::greater<>());
    queue.pop_back();
    while (!tree.nodes[n].children.empty()) {  // descend to the nearest leaf, queueing the siblings
      const Node& node = tree.nodes[n];
      int best = 0, best_d = INT_MAX;
      for (size_t c = 0; c < node.children.size(); ++c) {
        const int d = hammingDistance(query, node.centres.data() + c * blocks_, blocks_);
        if (d < best_d) {
          if (best_d != INT_MAX) push({best_d, t, node.children[best]});
          best_d = d, best = static_cast<int>(c);
        } else {
          push({d, t, node.children[c]});
        }
      }
      n = node.children[best];
    }
    // The leaf's words sit anywhere in the vocabulary: fetch them all before comparing.
    for (int32_t w : tree.nodes[n].words) {
      __builtin_prefetch(descriptorOf(w));
      __builtin_prefetch(&checked_[w]);
    }
    for (int32_t w : tree.nodes[n].words) {
      if (w == exclude || checked_[w] == stamp_) continue;
      checked_[w] = stamp_;
      const int d = hammingDistance(query, descriptorOf(w), blocks_);
      ++checks;
      if (d < out.first_distance) {
        out.second = out.first, out.second_distance = out.first_distance;
        out.first = w, out.first_distance = d;
      } else if (d < out.second_distance) {
        out.second = w, out.second_distance = d;
      }
    }
  }
  return out;
}

int WordTree::depthBelow(const Tree& tree, int32_t node) const {
  int d = 0;
  for (int32_t c : tree.nodes[node].children) d = std::max(d, depthBelow(tree, c));
  return d + 1;
}

int WordTree::depth() const { return depthBelow(trees_[0], 0); }

}  // namespace rmap::loop
