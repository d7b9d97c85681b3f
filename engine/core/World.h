#pragma once
// The entity-component world: entities are handles (Entity.h), components are plain structs
// stored per type in dense arrays (ComponentPool.h), and systems walk them through views.
//
// Structural changes while iterating. While any view is iterating, add, remove and destroy are
// recorded and applied, in the order they were made, when the outermost iteration ends. So a
// system may freely destroy the entity it is visiting, or add components to others: no reference
// it holds is invalidated, no entity is skipped or visited twice, and a view never sees changes
// made during its own pass. create() is immediate (a new entity has no components, so no running
// view can see it). Outside iteration, every change is immediate, and (as with std::vector) adding
// a component of type T may invalidate references to other T components.
//
// Misuse of a handle (a stale or null entity given to add/get/remove/destroy) is a precondition
// failure: the program stops with a message naming the entity. Use alive() or find() to ask.

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <tuple>
#include <type_traits>
#include <typeinfo>
#include <utility>
#include <vector>

#include "engine/core/ComponentPool.h"
#include "engine/core/Entity.h"
#include "base/Check.h"

namespace rhot {

namespace detail {
std::size_t next_component_type_id();
template <class T>
std::size_t component_type_id() {
  static const std::size_t id = next_component_type_id();
  return id;
}
std::string describe_entity(Entity e);
}  // namespace detail

class World;

// A view over every entity that has all of Ts. Obtained from World::view; cheap to make.
template <class... Ts>
class View {
  static_assert(sizeof...(Ts) > 0, "a view needs at least one component type");

 public:
  // Calls fn(Entity, Ts&...) or fn(Ts&...) for every entity with all of Ts. Walks the smallest of
  // the pools and looks the entity up in the others.
  template <class Fn>
  void each(Fn&& fn);

  // Number of entities in the smallest pool: an upper bound on how many each() visits.
  std::size_t size_hint() const;

 private:
  friend class World;
  explicit View(World& world);
  template <class Fn, std::size_t... K>
  void each_multi(Fn& fn, std::index_sequence<K...>);

  World* world_;
  std::tuple<ComponentPool<Ts>*...> pools_;
};

class World {
 public:
  World() = default;
  ~World() = default;
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  // Creates an entity with no components. Reuses the slot of a destroyed entity, with a new
  // generation, so old handles to that slot are stale.
  Entity create();

  // Destroys an entity and all its components; deferred while iterating. Precondition: alive(e).
  void destroy(Entity e);

  // True for a handle to an entity that exists (including one whose destruction is deferred).
  bool alive(Entity e) const;

  // Number of live entities.
  std::size_t size() const { return live_; }

  // Adds a component built from args, or replaces the entity's existing one. Deferred while
  // iterating. Precondition: alive(e).
  template <class T, class... Args>
  void add(Entity e, Args&&... args);

  // Removes a component if the entity has it; deferred while iterating. Precondition: alive(e).
  template <class T>
  void remove(Entity e);

  template <class T>
  bool has(Entity e) const;

  // The entity's component. Precondition: alive(e) and has<T>(e).
  template <class T>
  T& get(Entity e);
  template <class T>
  const T& get(Entity e) const;

  // The entity's component, or nullptr where the entity is stale or lacks one.
  template <class T>
  T* find(Entity e);
  template <class T>
  const T* find(Entity e) const;

  // Number of entities that have a T.
  template <class T>
  std::size_t count() const;

  template <class... Ts>
  View<Ts...> view() {
    return View<Ts...>(*this);
  }

  bool iterating() const { return iteration_depth_ > 0; }
  // Changes recorded during the current iteration, not yet applied.
  std::size_t pending_changes() const { return deferred_.size(); }

 private:
  template <class...>
  friend class View;

  // RAII: marks an iteration; the outermost one applies deferred changes when it ends.
  class IterationScope {
   public:
    explicit IterationScope(World& w) : world_(w) { ++world_.iteration_depth_; }
    ~IterationScope() {
      if (--world_.iteration_depth_ == 0) world_.apply_deferred();
    }
    IterationScope(const IterationScope&) = delete;
    IterationScope& operator=(const IterationScope&) = delete;

   private:
    World& world_;
  };

  template <class T>
  ComponentPool<T>* pool() const {
    const std::size_t id = detail::component_type_id<T>();
    return id < pools_.size() ? static_cast<ComponentPool<T>*>(pools_[id].get()) : nullptr;
  }
  template <class T>
  ComponentPool<T>& pool_or_create() {
    const std::size_t id = detail::component_type_id<T>();
    if (id >= pools_.size()) pools_.resize(id + 1);
    if (!pools_[id]) pools_[id] = std::make_unique<ComponentPool<T>>();
    return static_cast<ComponentPool<T>&>(*pools_[id]);
  }
  void require_alive(Entity e, const char* operation) const;
  template <class T>
  [[noreturn]] void missing_component(Entity e) const;
  void destroy_now(Entity e);
  void apply_deferred();

  // Generation of each slot. A slot whose generation reached kRetired is never reused.
  static constexpr std::uint32_t kRetired = 0xffffffffu;
  std::vector<std::uint32_t> generations_;
  std::vector<std::uint32_t> free_slots_;
  std::size_t live_ = 0;

  std::vector<std::unique_ptr<ComponentPoolBase>> pools_;  // indexed by component type id
  std::vector<std::move_only_function<void()>> deferred_;
  int iteration_depth_ = 0;
};

// ---- World templates ------------------------------------------------------------------------

template <class T, class... Args>
void World::add(Entity e, Args&&... args) {
  static_assert(std::is_same_v<T, std::remove_cvref_t<T>>, "component types are plain types");
  require_alive(e, "add");
  if (iterating()) {
    deferred_.emplace_back([this, e, value = T{std::forward<Args>(args)...}]() mutable {
      if (alive(e)) pool_or_create<T>().emplace_or_replace(e, std::move(value));
    });
    return;
  }
  pool_or_create<T>().emplace_or_replace(e, std::forward<Args>(args)...);
}

template <class T>
void World::remove(Entity e) {
  require_alive(e, "remove");
  ComponentPool<T>* p = pool<T>();
  if (p == nullptr) return;
  if (iterating()) {
    deferred_.emplace_back([this, e] {
      if (ComponentPool<T>* q = pool<T>()) q->remove(e);
    });
    return;
  }
  p->remove(e);
}

template <class T>
bool World::has(Entity e) const {
  const ComponentPool<T>* p = pool<T>();
  return p != nullptr && p->contains(e);
}

template <class T>
void World::missing_component(Entity e) const {
  RHOT_PRECONDITION(false, detail::describe_entity(e) + " has no component " + typeid(T).name());
  std::abort();
}

template <class T>
T& World::get(Entity e) {
  require_alive(e, "get");
  T* c = find<T>(e);
  if (c == nullptr) missing_component<T>(e);
  return *c;
}

template <class T>
const T& World::get(Entity e) const {
  require_alive(e, "get");
  const T* c = find<T>(e);
  if (c == nullptr) missing_component<T>(e);
  return *c;
}

template <class T>
T* World::find(Entity e) {
  ComponentPool<T>* p = pool<T>();
  return p != nullptr ? p->find(e) : nullptr;
}

template <class T>
const T* World::find(Entity e) const {
  const ComponentPool<T>* p = pool<T>();
  return p != nullptr ? p->find(e) : nullptr;
}

template <class T>
std::size_t World::count() const {
  const ComponentPool<T>* p = pool<T>();
  return p != nullptr ? p->size() : 0;
}

// ---- View templates -------------------------------------------------------------------------

template <class... Ts>
View<Ts...>::View(World& world) : world_(&world), pools_(world.pool<Ts>()...) {}

template <class... Ts>
std::size_t View<Ts...>::size_hint() const {
  std::size_t smallest = ~std::size_t{0};
  bool missing = false;
  std::apply(
      [&](auto*... p) {
        ((missing = missing || p == nullptr), ...);
        if (!missing) ((smallest = std::min(smallest, p->size())), ...);
      },
      pools_);
  return missing ? 0 : smallest;
}

template <class... Ts>
template <class Fn>
void View<Ts...>::each(Fn&& fn) {
  if (size_hint() == 0) return;
  World::IterationScope scope(*world_);

  if constexpr (sizeof...(Ts) == 1) {
    // One type: walk the dense arrays directly.
    auto* p = std::get<0>(pools_);
    const std::span<const Entity> entities = p->entities();
    const auto components = p->components();
    for (std::size_t i = 0; i < entities.size(); ++i) {
      if constexpr (std::is_invocable_v<Fn&, Entity, Ts&...>) {
        fn(entities[i], components[i]);
      } else {
        fn(components[i]);
      }
    }
  } else {
    each_multi(fn, std::index_sequence_for<Ts...>{});
  }
}

template <class... Ts>
template <class Fn, std::size_t... K>
void View<Ts...>::each_multi(Fn& fn, std::index_sequence<K...>) {
  // Walk the smallest pool by position; look each entity up once in every other pool.
  std::size_t lead = 0;
  std::size_t lead_size = ~std::size_t{0};
  ((std::get<K>(pools_)->size() < lead_size ? (lead = K, lead_size = std::get<K>(pools_)->size()) : 0), ...);
  const ComponentPoolBase* lead_pool = nullptr;
  ((K == lead ? (lead_pool = std::get<K>(pools_), 0) : 0), ...);

  // Pools do not change shape during the scope (changes are deferred), so the span is stable.
  const std::span<const Entity> entities = lead_pool->entities();
  std::array<std::uint32_t, sizeof...(Ts)> at{};
  for (std::size_t i = 0; i < entities.size(); ++i) {
    const Entity e = entities[i];
    const bool all =
        ((at[K] = (K == lead ? static_cast<std::uint32_t>(i) : std::get<K>(pools_)->index_of(e, i)), at[K] != ComponentPool<Ts>::kAbsent) &&
         ...);
    if (!all) continue;
    if constexpr (std::is_invocable_v<Fn&, Entity, Ts&...>) {
      fn(e, std::get<K>(pools_)->components()[at[K]]...);
    } else {
      fn(std::get<K>(pools_)->components()[at[K]]...);
    }
  }
}

}  // namespace rhot
