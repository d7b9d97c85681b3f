#include "engine/core/World.h"

#include <atomic>

namespace rhot {

namespace detail {
std::size_t next_component_type_id() {
  static std::atomic<std::size_t> next{0};
  return next.fetch_add(1, std::memory_order_relaxed);
}

std::string describe_entity(Entity e) {
  if (e.is_null()) return "null entity";
  return "entity " + std::to_string(e.index) + " (generation " + std::to_string(e.generation) + ")";
}
}  // namespace detail

Entity World::create() {
  ++live_;
  if (!free_slots_.empty()) {
    const std::uint32_t index = free_slots_.back();
    free_slots_.pop_back();
    return Entity{index, generations_[index]};
  }
  RHOT_PRECONDITION(generations_.size() < Entity::kInvalidIndex, "World::create: out of entity slots");
  generations_.push_back(0);
  return Entity{static_cast<std::uint32_t>(generations_.size() - 1), 0};
}

bool World::alive(Entity e) const {
  return e.index < generations_.size() && generations_[e.index] == e.generation && e.generation != kRetired;
}

void World::require_alive(Entity e, const char* operation) const {
  if (alive(e)) [[likely]]
    return;
  RHOT_PRECONDITION(false, std::string("World::") + operation + ": " + detail::describe_entity(e) +
                               (e.is_null() ? "" : " is stale (destroyed, or from another world)"));
}

void World::destroy(Entity e) {
  require_alive(e, "destroy");
  if (iterating()) {
    deferred_.emplace_back([this, e] {
      if (alive(e)) destroy_now(e);
    });
    return;
  }
  destroy_now(e);
}

void World::destroy_now(Entity e) {
  for (const auto& p : pools_) {
    if (p) p->remove(e);
  }
  // A new generation makes every existing handle stale. A slot that has used up its generations
  // is retired rather than wrapped around, so a stale handle can never come back to life.
  const std::uint32_t next = ++generations_[e.index];
  if (next != kRetired) free_slots_.push_back(e.index);
  --live_;
}

void World::apply_deferred() {
  // Commands run outside any iteration, so they apply directly and enqueue nothing.
  std::vector<std::move_only_function<void()>> commands;
  commands.swap(deferred_);
  for (auto& command : commands) command();
}

}  // namespace rhot
