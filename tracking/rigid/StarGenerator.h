#pragma once
// Generating a set of marker stars (after seed 003, "A method for designing marker stars"): as
// many stars as fit in a box, every face of every star telling itself apart from every other face
// in the set, so a star is known from any three of its markers.
//
// The seed builds tetrahedra from a pool of edge lengths and keeps those whose oriented bounding
// box fits. rhot draws random tetrahedra directly inside the box (every star that fits the box in
// some orientation can be drawn in that orientation), keeps those that satisfy the rules on their
// own, and then packs them greedily, trying several orders and keeping the largest set: faces are
// points in the space of sorted edge triples that must stay `variation` apart, and the order in
// which candidates are offered decides how densely they pack.

#include <expected>
#include <functional>
#include <string>

#include "tracking/rigid/StarSet.h"

namespace rhot {

struct StarGeneratorSettings {
  StarSetRules rules;
  int candidates = 300000;  // valid random stars to choose from (more: a denser set, slower)
  unsigned seed = 1;
  int max_stars = 0;  // stop after this many (0: as many as fit)
};

// Called now and then with (work done, total work).
using GeneratorProgress = std::function<void(long done, long total)>;

// A valid set (check_star_set finds nothing), or a message naming the argument that is wrong or
// saying that not even one star fits.
[[nodiscard]] std::expected<StarSet, std::string> generate_star_set(const StarGeneratorSettings& settings,
                                                                    const GeneratorProgress& progress = {});

}  // namespace rhot
