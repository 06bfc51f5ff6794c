#include "loop/inverted_index.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace rmap::loop {

void InvertedIndex::addFrame(std::span<const WordId> words) {
  const auto frame = static_cast<int32_t>(frame_features_.size());
  uint32_t features = 0;
  for (WordId w : words) {
    if (w < 0) continue;
    ++features;
    if (static_cast<size_t>(w) >= postings_.size()) postings_.resize(static_cast<size_t>(w) + 1);
    std::vector<Posting>& p = postings_[w];
    if (!p.empty() && p.back().frame == frame) {
      if (p.back().count < UINT16_MAX) ++p.back().count;
    } else {
      p.push_back({frame, 1});
    }
  }
  frame_features_.push_back(features);
}

void InvertedIndex::mergeWords(WordId keep, WordId gone) {
  if (gone < 0 || static_cast<size_t>(gone) >= postings_.size() || keep == gone) return;
  if (static_cast<size_t>(keep) >= postings_.size()) postings_.resize(static_cast<size_t>(keep) + 1);
  std::vector<Posting> merged;
  const std::vector<Posting>& a = postings_[keep];
  const std::vector<Posting>& b = postings_[gone];
  merged.reserve(a.size() + b.size());
  size_t i = 0, j = 0;
  while (i < a.size() || j < b.size()) {
    if (j == b.size() || (i < a.size() && a[i].frame < b[j].frame)) {
      merged.push_back(a[i++]);
    } else if (i == a.size() || b[j].frame < a[i].frame) {
      merged.push_back(b[j++]);
    } else {
      const int c = std::min<int>(a[i].count + b[j].count, UINT16_MAX);
      merged.push_back({a[i].frame, static_cast<uint16_t>(c)});
      ++i, ++j;
    }
  }
  postings_[keep] = std::move(merged);
  postings_[gone] = {};
}

void InvertedIndex::removeWord(WordId word) {
  if (word >= 0 && static_cast<size_t>(word) < postings_.size()) postings_[word] = {};
}

size_t InvertedIndex::documentFrequency(WordId word) const {
  return word >= 0 && static_cast<size_t>(word) < postings_.size() ? postings_[word].size() : 0;
}

int InvertedIndex::count(WordId word, int64_t frame) const {
  if (word < 0 || static_cast<size_t>(word) >= postings_.size()) return 0;
  const std::vector<Posting>& p = postings_[word];
  auto it = std::lower_bound(p.begin(), p.end(), frame, [](const Posting& q, int64_t f) { return q.frame < f; });
  return it != p.end() && it->frame == frame ? it->count : 0;
}

std::vector<FrameScore> InvertedIndex::score(std::span<const WordId> query_words, int64_t before_frame) const {
  std::unordered_map<WordId, int> histogram;
  int features = 0;
  for (WordId w : query_words) {
    if (w < 0) continue;
    ++histogram[w];
    ++features;
  }
  std::vector<FrameScore> out;
  if (features == 0) return out;
  const double n = static_cast<double>(frames());
  accumulator_.resize(frame_features_.size(), 0.0);
  std::vector<int32_t> touched;
  double self = 0.0;
  for (const auto& [w, c] : histogram) {
    const size_t df = documentFrequency(w);
    const double idf = std::log((n + 1.0) / (static_cast<double>(df) + 1.0));
    const double tf_q = static_cast<double>(c) / features;
    self += idf * tf_q;
    if (df == 0 || idf <= 0.0) continue;
    for (const Posting& p : postings_[w]) {
      if (p.frame >= before_frame) break;
      const double tf_f = static_cast<double>(p.count) / frame_features_[p.frame];
      if (accumulator_[p.frame] == 0.0) touched.push_back(p.frame);
      accumulator_[p.frame] += idf * std::min(tf_q, tf_f);
    }
  }
  out.reserve(touched.size());
  for (int32_t f : touched) {
    out.push_back({f, self > 0.0 ? accumulator_[f] / self : 0.0});
    accumulator_[f] = 0.0;
  }
  return out;
}

}  // namespace rmap::loop
