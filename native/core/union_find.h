// core/union_find.h — disjoint sets with path halving and union by index (deterministic:
// the smaller index becomes the root, so component ids do not depend on merge order).
#pragma once
#include <numeric>
#include <vector>

namespace genbrep {

class UnionFind {
 public:
  explicit UnionFind(int n) : parent_(static_cast<size_t>(n)) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  int find(int x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (a < b) parent_[b] = a; else parent_[a] = b;
  }

 private:
  std::vector<int> parent_;
};

}  // namespace genbrep
