#pragma once
// Entity handles: a slot index plus a generation counter. Destroying an entity bumps its slot's
// generation, so every handle to it goes stale; a stale handle is detected (World::alive is false)
// rather than silently reaching whatever entity reuses the slot later.

#include <cstdint>
#include <functional>

namespace rhot {

struct Entity {
  static constexpr std::uint32_t kInvalidIndex = 0xffffffffu;

  std::uint32_t index = kInvalidIndex;
  std::uint32_t generation = 0;

  constexpr bool is_null() const { return index == kInvalidIndex; }
  friend constexpr bool operator==(Entity, Entity) = default;
};

inline constexpr Entity kNullEntity{};

}  // namespace rhot

template <>
struct std::hash<rhot::Entity> {
  std::size_t operator()(rhot::Entity e) const noexcept {
    return std::hash<std::uint64_t>{}((std::uint64_t{e.generation} << 32) | e.index);
  }
};
