#pragma once
// Grouping by an integer key (counting sort), for adjacency lists: vertex → cells, vertex → stencil groups,
// colour → elements (internal to fem/).
#include <vector>

namespace snh {

/// Items grouped by key: items[start[k] .. start[k+1]) have key k, in the order emitted.
struct Buckets {
  std::vector<int> start, items;
};

/// Groups the (key, item) pairs that for_each_pair(emit) emits, keys in [0, keys). for_each_pair must call
/// emit(key, item) for every pair, the same way each time (it is called twice: to count, then to fill).
template <class ForEachPair>
Buckets bucket(int keys, ForEachPair&& for_each_pair) {
  Buckets b;
  b.start.assign(keys + 1, 0);
  for_each_pair([&](int key, int) { ++b.start[key + 1]; });
  for (int k = 0; k < keys; ++k) b.start[k + 1] += b.start[k];
  b.items.resize(b.start[keys]);
  std::vector<int> fill(b.start.begin(), b.start.end() - 1);
  for_each_pair([&](int key, int item) { b.items[fill[key]++] = item; });
  return b;
}

}  // namespace snh
