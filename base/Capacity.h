#pragma once
// Room kept ahead in the vectors that a frame's work empties and fills again (matching, star
// identification, the trackers' working storage): a vector that must hold n grows to twice that,
// so that once frames have shown it their largest counts, a later frame that holds a few more does
// not allocate it again (std::vector's assign and resize take exactly what they are
// asked for). After the first frames the tracking allocates nothing (docs/tracking.md "Threads").

#include <cstddef>
#include <vector>

namespace rhot {

template <class T, class Allocator>
void reserve_room(std::vector<T, Allocator>& v, std::size_t n) {
  if (v.capacity() < n) v.reserve(2 * n + 16);
}

}  // namespace rhot
