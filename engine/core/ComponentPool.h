#pragma once
// Storage for one component type: a sparse set. Components sit densely packed in one vector (so a
// view walks contiguous memory), with a sparse table from entity slot index to dense position.
// Removal swaps the last element into the hole: O(1), order not kept.
//
// Only World touches pools directly; it guarantees that no pool changes shape while a view
// iterates (structural changes are deferred), which is what keeps references stable there.

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "engine/core/Entity.h"

namespace rhot {

class ComponentPoolBase {
 public:
  virtual ~ComponentPoolBase() = default;
  virtual bool contains(Entity e) const = 0;
  virtual void remove(Entity e) = 0;  // no-op when absent
  virtual std::size_t size() const = 0;
  virtual std::span<const Entity> entities() const = 0;
};

template <class T>
class ComponentPool final : public ComponentPoolBase {
 public:
  static constexpr std::uint32_t kAbsent = 0xffffffffu;

  bool contains(Entity e) const override {
    return e.index < sparse_.size() && sparse_[e.index] != kAbsent && entities_[sparse_[e.index]] == e;
  }

  // Adds the component, or replaces the value an entity already has.
  template <class... Args>
  T& emplace_or_replace(Entity e, Args&&... args) {
    if (contains(e)) {
      T& slot = components_[sparse_[e.index]];
      slot = T{std::forward<Args>(args)...};
      return slot;
    }
    if (e.index >= sparse_.size()) sparse_.resize(std::size_t{e.index} + 1, kAbsent);
    sparse_[e.index] = static_cast<std::uint32_t>(entities_.size());
    entities_.push_back(e);
    components_.push_back(T{std::forward<Args>(args)...});
    return components_.back();
  }

  void remove(Entity e) override {
    if (!contains(e)) return;
    const std::uint32_t hole = sparse_[e.index];
    const std::uint32_t last = static_cast<std::uint32_t>(entities_.size() - 1);
    if (hole != last) {
      entities_[hole] = entities_[last];
      components_[hole] = std::move(components_[last]);
      sparse_[entities_[hole].index] = hole;
    }
    entities_.pop_back();
    components_.pop_back();
    sparse_[e.index] = kAbsent;
  }

  // Dense position of e's component, or kAbsent: one lookup for views that then index directly.
  std::uint32_t index_of(Entity e) const {
    if (e.index >= sparse_.size()) return kAbsent;
    const std::uint32_t i = sparse_[e.index];
    return (i != kAbsent && entities_[i] == e) ? i : kAbsent;
  }

  // index_of with a guess: pools filled in the same order keep an entity at the same position,
  // so a view checks its own position first and skips the sparse lookup.
  std::uint32_t index_of(Entity e, std::size_t guess) const {
    return (guess < entities_.size() && entities_[guess] == e) ? static_cast<std::uint32_t>(guess) : index_of(e);
  }

  T* find(Entity e) { return contains(e) ? &components_[sparse_[e.index]] : nullptr; }
  const T* find(Entity e) const { return contains(e) ? &components_[sparse_[e.index]] : nullptr; }

  std::size_t size() const override { return entities_.size(); }
  std::span<const Entity> entities() const override { return entities_; }
  std::span<T> components() { return components_; }
  std::span<const T> components() const { return components_; }

 private:
  std::vector<std::uint32_t> sparse_;  // entity slot index -> dense position, or kAbsent
  std::vector<Entity> entities_;       // dense, parallel to components_
  std::vector<T> components_;
};

}  // namespace rhot
