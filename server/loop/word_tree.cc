#include "loop/word_tree.h"

#include <algorithm>
#include <climits>
#include <queue>
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
  require(max_checks >= 1, "max_checks must be >= 1");
}

WordTree::WordTree(const std::vector<uint64_t>* descriptors, int blocks, WordTreeOptions options)
    : descriptors_(descriptors), blocks_(blocks), options_(options), rng_(options.seed) {
  options_.validate();
  if (descriptors_ == nullptr || blocks_ < 1) throw std::invalid_argument("WordTree: no descriptor storage");
  nodes_.emplace_back();
}

const uint64_t* WordTree::descriptorOf(int32_t word) const {
  return descriptors_->data() + static_cast<size_t>(word) * blocks_;
}

int32_t WordTree::leafFor(const uint64_t* d) const {
  int32_t n = 0;
  while (!nodes_[n].children.empty()) {
    const Node& node = nodes_[n];
    int best = 0, best_d = INT_MAX;
    for (size_t c = 0; c < node.children.size(); ++c) {
      const int dc = hammingDistance(d, node.centres.data() + c * blocks_, blocks_);
      if (dc < best_d) best_d = dc, best = static_cast<int>(c);
    }
    n = node.children[best];
  }
  return n;
}

void WordTree::insert(int32_t word) {
  if (word < 0) throw std::invalid_argument("WordTree::insert: negative word id");
  if (static_cast<size_t>(word) >= leaf_of_.size()) leaf_of_.resize(static_cast<size_t>(word) + 1, -1);
  if (leaf_of_[word] >= 0) throw std::invalid_argument("WordTree::insert: word already in the tree");
  const int32_t leaf = leafFor(descriptorOf(word));
  nodes_[leaf].words.push_back(word);
  leaf_of_[word] = leaf;
  ++words_;
  if (static_cast<int>(nodes_[leaf].words.size()) > options_.leaf_size) split(leaf);
}

void WordTree::remove(int32_t word) {
  if (word < 0 || static_cast<size_t>(word) >= leaf_of_.size() || leaf_of_[word] < 0) return;
  std::vector<int32_t>& ws = nodes_[leaf_of_[word]].words;
  auto it = std::find(ws.begin(), ws.end(), word);
  *it = ws.back();
  ws.pop_back();
  leaf_of_[word] = -1;
  --words_;
}

void WordTree::split(int32_t node) {
  std::vector<int32_t> words = std::move(nodes_[node].words);
  nodes_[node].words.clear();
  // k-means++ seeding: each next centre drawn with probability ∝ squared distance to the chosen ones.
  const int k = options_.branching;
  std::vector<int> nearest(words.size(), INT_MAX);
  std::vector<int32_t> centre_words;
  centre_words.push_back(words[std::uniform_int_distribution<size_t>(0, words.size() - 1)(rng_)]);
  while (static_cast<int>(centre_words.size()) < k) {
    double total = 0.0;
    for (size_t i = 0; i < words.size(); ++i) {
      const int d = hammingDistance(descriptorOf(words[i]), descriptorOf(centre_words.back()), blocks_);
      nearest[i] = std::min(nearest[i], d);
      total += static_cast<double>(nearest[i]) * nearest[i];
    }
    if (total == 0.0) break;  // the remaining words duplicate the centres
    double pick = std::uniform_real_distribution<double>(0.0, total)(rng_);
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
    nodes_[node].words = std::move(words);
    return;
  }
  std::vector<uint64_t> centres(centre_words.size() * blocks_);
  for (size_t c = 0; c < centre_words.size(); ++c) {
    std::copy_n(descriptorOf(centre_words[c]), blocks_, centres.begin() + c * blocks_);
  }
  std::vector<int32_t> children;
  for (size_t c = 0; c < centre_words.size(); ++c) {
    children.push_back(static_cast<int32_t>(nodes_.size()));
    nodes_.emplace_back();
  }
  for (int32_t w : words) {
    int best = 0, best_d = INT_MAX;
    for (size_t c = 0; c < centre_words.size(); ++c) {
      const int d = hammingDistance(descriptorOf(w), centres.data() + c * blocks_, blocks_);
      if (d < best_d) best_d = d, best = static_cast<int>(c);
    }
    nodes_[children[best]].words.push_back(w);
    leaf_of_[w] = children[best];
  }
  nodes_[node].centres = std::move(centres);
  nodes_[node].children = std::move(children);
}

NearestWords WordTree::search(const uint64_t* query, int32_t exclude) const {
  NearestWords out;
  out.first_distance = out.second_distance = INT_MAX;
  using Branch = std::pair<int, int32_t>;  // (centre distance, node)
  std::priority_queue<Branch, std::vector<Branch>, std::greater<>> queue;
  queue.push({0, 0});
  int checks = 0;
  while (!queue.empty() && checks < options_.max_checks) {
    int32_t n = queue.top().second;
    queue.pop();
    while (!nodes_[n].children.empty()) {  // descend to the nearest leaf, queueing the siblings
      const Node& node = nodes_[n];
      int best = 0, best_d = INT_MAX;
      for (size_t c = 0; c < node.children.size(); ++c) {
        const int d = hammingDistance(query, node.centres.data() + c * blocks_, blocks_);
        if (d < best_d) {
          if (best_d != INT_MAX) queue.push({best_d, node.children[best]});
          best_d = d, best = static_cast<int>(c);
        } else {
          queue.push({d, node.children[c]});
        }
      }
      n = node.children[best];
    }
    for (int32_t w : nodes_[n].words) {
      if (w == exclude) continue;
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

int WordTree::depthBelow(int32_t node) const {
  int d = 0;
  for (int32_t c : nodes_[node].children) d = std::max(d, depthBelow(c));
  return d + 1;
}

int WordTree::depth() const { return depthBelow(0); }

}  // namespace rmap::loop
