#pragma once
// Per-cell work arrays of the reconstructions that outlive a rebuild: no allocation per step once they are large
// enough.
#include <cstddef>
#include <memory>
#include <vector>

namespace mpm {

class ScratchStore {
 public:
  /// Storage of type T for n items, one store per type (the two rebuilds of a MUSL step use different ones;
  /// sharing one store reallocated it twice a step: 8 % of a 1e6-particle TLS step went to its page faults).
  template <class T>
  std::vector<T>& get(std::size_t n) {
    Items<T>* s = nullptr;
    for (const auto& store : stores_)
      if ((s = dynamic_cast<Items<T>*>(store.get()))) break;
    if (!s) {
      auto fresh = std::make_unique<Items<T>>();
      s = fresh.get();
      stores_.push_back(std::move(fresh));
    }
    s->items.resize(n);
    return s->items;
  }

 private:
  struct Base {
    virtual ~Base() = default;
  };
  template <class T>
  struct Items : Base {
    std::vector<T> items;
  };
  std::vector<std::unique_ptr<Base>> stores_;
};

}  // namespace mpm
