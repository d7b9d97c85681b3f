// ECS iteration cost: a view over entities with two components, as a physics or tracking system
// walks them every frame. Results: docs/PERFORMANCE.md.

#include <benchmark/benchmark.h>

#include "engine/core/World.h"

namespace {

struct Position {
  float x, y, z;
};
struct Velocity {
  float x, y, z;
};

// Every entity has both components.
void BM_ViewTwoComponents(benchmark::State& state) {
  rhot::World world;
  const auto n = static_cast<int>(state.range(0));
  for (int i = 0; i < n; ++i) {
    const rhot::Entity e = world.create();
    world.add<Position>(e, Position{static_cast<float>(i), 0.0f, 0.0f});
    world.add<Velocity>(e, Velocity{1.0f, 2.0f, 3.0f});
  }
  constexpr float dt = 1.0f / 90.0f;
  for (auto _ : state) {
    world.view<Position, Velocity>().each([](Position& p, const Velocity& v) {
      p.x += v.x * dt;
      p.y += v.y * dt;
      p.z += v.z * dt;
    });
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_ViewTwoComponents)->Arg(1000)->Arg(100000)->Unit(benchmark::kMicrosecond);

// Half the entities have a Velocity, interleaved: the view skips the others.
void BM_ViewTwoComponentsSparse(benchmark::State& state) {
  rhot::World world;
  const auto n = static_cast<int>(state.range(0));
  for (int i = 0; i < n; ++i) {
    const rhot::Entity e = world.create();
    world.add<Position>(e, Position{static_cast<float>(i), 0.0f, 0.0f});
    if (i % 2 == 0) world.add<Velocity>(e, Velocity{1.0f, 2.0f, 3.0f});
  }
  for (auto _ : state) {
    world.view<Position, Velocity>().each([](Position& p, const Velocity& v) { p.x += v.x; });
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_ViewTwoComponentsSparse)->Arg(1000)->Arg(100000)->Unit(benchmark::kMicrosecond);

// The baseline a dense ECS cannot beat: the same update over two plain arrays.
void BM_PlainArrays(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  std::vector<Position> positions(n, Position{0.0f, 0.0f, 0.0f});
  std::vector<Velocity> velocities(n, Velocity{1.0f, 2.0f, 3.0f});
  constexpr float dt = 1.0f / 90.0f;
  for (auto _ : state) {
    for (std::size_t i = 0; i < n; ++i) {
      positions[i].x += velocities[i].x * dt;
      positions[i].y += velocities[i].y * dt;
      positions[i].z += velocities[i].z * dt;
    }
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(n));
}
BENCHMARK(BM_PlainArrays)->Arg(1000)->Arg(100000)->Unit(benchmark::kMicrosecond);

// Creating and destroying entities with components, as spawning does.
void BM_CreateDestroy(benchmark::State& state) {
  rhot::World world;
  const auto n = static_cast<int>(state.range(0));
  std::vector<rhot::Entity> es(static_cast<std::size_t>(n));
  for (auto _ : state) {
    for (auto& e : es) {
      e = world.create();
      world.add<Position>(e, Position{0.0f, 0.0f, 0.0f});
      world.add<Velocity>(e, Velocity{0.0f, 0.0f, 0.0f});
    }
    for (const auto e : es) world.destroy(e);
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_CreateDestroy)->Arg(1000)->Arg(100000)->Unit(benchmark::kMicrosecond);

}  // namespace
