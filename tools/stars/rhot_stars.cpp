// rhot-stars: generates a set of marker stars for a box, marker size and variation, with a
// printable mesh per star and a picture of the set.
//
//   rhot-stars --marker-diameter-mm 4 --box-mm 20.8 12.6 48.3 --variation-mm 1.5 --out stars.json
//
// writes stars.json (the set: docs/marker-stars.md), stars-star-<id>.stl (one printable star
// each: marker spheres on struts over a base plate) and stars.svg (every star from the front and
// the side, in its box).

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

// GCC 12 at -O2 reports a null dereference inside CLI11's string splitting once it is inlined here
// (a false positive in libstdc++'s string move); the pragma covers only CLI11's lines.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <CLI/CLI.hpp>
#pragma GCC diagnostic pop
#include <Eigen/Geometry>

#include "tracking/rigid/StarGenerator.h"
#include "tracking/rigid/StarSet.h"
#include "tools/common/CliExit.h"
#include "tools/common/NumberChecks.h"

namespace {

namespace fs = std::filesystem;

struct Triangle {
  Eigen::Vector3f a, b, c;
};

void add_sphere(std::vector<Triangle>& out, const Eigen::Vector3d& centre, double radius, int slices = 24, int stacks = 12) {
  auto at = [&](int i, int j) {
    const double theta = std::numbers::pi * j / stacks;
    const double phi = 2.0 * std::numbers::pi * i / slices;
    Eigen::Vector3d p;
    p << std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta);
    p = centre + radius * p;
    return Eigen::Vector3f(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  };
  for (int j = 0; j < stacks; ++j) {
    for (int i = 0; i < slices; ++i) {
      const Eigen::Vector3f p00 = at(i, j), p10 = at(i + 1, j), p01 = at(i, j + 1), p11 = at(i + 1, j + 1);
      if (j > 0) out.push_back({p00, p01, p10});
      if (j + 1 < stacks) out.push_back({p10, p01, p11});
    }
  }
}

// A closed cylinder from a to b (a above b or not; any direction).
void add_cylinder(std::vector<Triangle>& out, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius, int slices = 16) {
  const Eigen::Vector3d axis = (b - a).normalized();
  const Eigen::Vector3d u = axis.unitOrthogonal();
  const Eigen::Vector3d v = axis.cross(u);
  for (int i = 0; i < slices; ++i) {
    const double p0 = 2.0 * std::numbers::pi * i / slices, p1 = 2.0 * std::numbers::pi * (i + 1) / slices;
    const Eigen::Vector3d r0 = radius * (std::cos(p0) * u + std::sin(p0) * v), r1 = radius * (std::cos(p1) * u + std::sin(p1) * v);
    const Eigen::Vector3f a0 = (a + r0).cast<float>(), a1 = (a + r1).cast<float>(), b0 = (b + r0).cast<float>(),
                          b1 = (b + r1).cast<float>();
    out.push_back({a0, b0, a1});
    out.push_back({a1, b0, b1});
    out.push_back({a.cast<float>(), a0, a1});  // caps
    out.push_back({b.cast<float>(), b1, b0});
  }
}

void add_box(std::vector<Triangle>& out, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  auto corner = [&](int i) {
    return Eigen::Vector3f(float(i & 1 ? hi.x() : lo.x()), float(i & 2 ? hi.y() : lo.y()), float(i & 4 ? hi.z() : lo.z()));
  };
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    out.push_back({corner(q[0]), corner(q[1]), corner(q[2])});
    out.push_back({corner(q[0]), corner(q[2]), corner(q[3])});
  }
}

bool write_stl(const fs::path& file, const std::vector<Triangle>& triangles, const std::string& name) {
  std::ofstream out(file, std::ios::binary);
  if (!out) return false;
  std::array<char, 80> header{};
  std::snprintf(header.data(), header.size(), "rhot marker star %s (millimetres)", name.c_str());
  out.write(header.data(), header.size());
  const auto count = static_cast<std::uint32_t>(triangles.size());
  out.write(reinterpret_cast<const char*>(&count), 4);
  for (const Triangle& t : triangles) {
    const Eigen::Vector3f n = (t.b - t.a).cross(t.c - t.a).normalized();
    for (const Eigen::Vector3f& v : {n, t.a, t.b, t.c}) out.write(reinterpret_cast<const char*>(v.data()), 12);
    const std::uint16_t attributes = 0;
    out.write(reinterpret_cast<const char*>(&attributes), 2);
  }
  return static_cast<bool>(out);
}

// Spheres of the marker diameter on struts (a third of it thick) standing on a 2 mm plate under
// the box (z from -2 to 0), the plate as wide as the markers above it.
std::vector<Triangle> star_mesh(const rhot::MarkerStar& star, double diameter) {
  std::vector<Triangle> t;
  Eigen::Vector3d lo = star.markers_mm[0], hi = star.markers_mm[0];
  for (const Eigen::Vector3d& m : star.markers_mm) {
    add_sphere(t, m, 0.5 * diameter);
    add_cylinder(t, m, Eigen::Vector3d(m.x(), m.y(), 0.0), diameter / 6.0);
    lo = lo.cwiseMin(m);
    hi = hi.cwiseMax(m);
  }
  const double r = 0.5 * diameter;
  add_box(t, Eigen::Vector3d(lo.x() - r, lo.y() - r, -2.0), Eigen::Vector3d(hi.x() + r, hi.y() + r, 0.0));
  return t;
}

// Every star from the front (x right, z up) and from the side (y right, z up), inside its box.
std::string svg(const rhot::StarSet& set) {
  const rhot::StarSetRules& r = set.rules;
  const double scale = 4.0;  // pixels per millimetre
  const double pad = 12.0;
  const double cell_w = (r.box_mm.x() + r.box_mm.y()) * scale + 3 * pad;
  const double cell_h = r.box_mm.z() * scale + 2 * pad + 14;
  const int columns = std::max(1, std::min(10, static_cast<int>(set.stars.size())));
  const int rows = std::max(1, (static_cast<int>(set.stars.size()) + columns - 1) / columns);
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << columns * cell_w << "\" height=\"" << rows * cell_h + 30 << "\">\n";
  s << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  s << "<text x=\"8\" y=\"20\" font-family=\"sans-serif\" font-size=\"14\">" << set.stars.size() << " marker stars, "
    << r.marker_diameter_mm << " mm markers, box " << r.box_mm.x() << " x " << r.box_mm.y() << " x " << r.box_mm.z() << " mm, variation "
    << r.variation_mm << " mm (front: x right, z up; side: y right, z up)</text>\n";
  for (std::size_t i = 0; i < set.stars.size(); ++i) {
    const rhot::MarkerStar& star = set.stars[i];
    const double ox = static_cast<double>(i % static_cast<std::size_t>(columns)) * cell_w;
    const double oy = 30 + static_cast<double>(i / static_cast<std::size_t>(columns)) * cell_h;
    s << "<text x=\"" << ox + pad << "\" y=\"" << oy + 12 << "\" font-family=\"sans-serif\" font-size=\"12\">star " << star.id
      << "</text>\n";
    for (int view = 0; view < 2; ++view) {
      const double width = view == 0 ? r.box_mm.x() : r.box_mm.y();
      const double vx = ox + pad + (view == 0 ? 0.0 : r.box_mm.x() * scale + pad);
      const double vy = oy + 16;
      auto px = [&](const Eigen::Vector3d& p) { return vx + ((view == 0 ? p.x() : p.y()) + 0.5 * width) * scale; };
      auto py = [&](const Eigen::Vector3d& p) { return vy + (r.box_mm.z() - p.z()) * scale; };
      s << "<rect x=\"" << vx << "\" y=\"" << vy << "\" width=\"" << width * scale << "\" height=\"" << r.box_mm.z() * scale
        << "\" fill=\"none\" stroke=\"#999\"/>\n";
      for (const auto& e : rhot::kStarEdges) {
        const Eigen::Vector3d& a = star.markers_mm[static_cast<std::size_t>(e[0])];
        const Eigen::Vector3d& b = star.markers_mm[static_cast<std::size_t>(e[1])];
        s << "<line x1=\"" << px(a) << "\" y1=\"" << py(a) << "\" x2=\"" << px(b) << "\" y2=\"" << py(b) << "\" stroke=\"#555\"/>\n";
      }
      for (std::size_t m = 0; m < 4; ++m) {
        const Eigen::Vector3d& p = star.markers_mm[m];
        s << "<circle cx=\"" << px(p) << "\" cy=\"" << py(p) << "\" r=\"" << 0.5 * r.marker_diameter_mm * scale
          << "\" fill=\"#f0a030\" stroke=\"black\"/>\n";
      }
    }
  }
  s << "</svg>\n";
  return s.str();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rhot-stars: generate marker stars whose every face is unique in the set, with printable meshes and a picture"};
  rhot::StarGeneratorSettings settings;
  double diameter = 4.0;
  std::vector<double> box{20.8, 12.6, 48.3};
  double variation = 1.5;
  std::string out;
  bool no_meshes = false;
  app.add_option("--marker-diameter-mm", diameter, "marker sphere diameter")->capture_default_str();
  app.add_option("--box-mm", box, "the box every star must fit, X Y Z (Z: the long side, the star stands on X x Y)")
      ->expected(3)
      ->capture_default_str();
  app.add_option("--variation-mm", variation, "least difference between edge lengths the tracker must tell apart")->capture_default_str();
  app.add_option("--out", out, "the star set (JSON); meshes and the picture go beside it")->required();
  app.add_option("--candidates", settings.candidates, "random stars to choose from (more: a denser set, slower)")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000000));
  app.add_option("--seed", settings.seed, "random seed")->capture_default_str();
  app.add_option("--max-stars", settings.max_stars, "stop after this many stars (0: as many as fit)")
      ->capture_default_str()
      ->check(rhot::number_check(rhot::NumberBound::kNonNegative));
  app.add_flag("--no-meshes", no_meshes, "write the JSON and the picture only");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return rhot::cli_exit_status(app, e);
  }

  settings.rules.marker_diameter_mm = diameter;
  settings.rules.box_mm = {box[0], box[1], box[2]};
  settings.rules.variation_mm = variation;
  int last_percent = -1;
  const auto set = rhot::generate_star_set(settings, [&](long done, long total) {
    const int percent = static_cast<int>(100 * done / std::max(1L, total));
    if (percent / 10 != last_percent / 10) std::cerr << "rhot-stars: drawing candidates " << percent << " %\n";
    last_percent = percent;
  });
  if (!set) {
    std::cerr << "rhot-stars: " << set.error() << "\n";
    return 1;
  }
  if (const auto problems = rhot::check_star_set(*set); !problems.empty()) {
    std::cerr << "rhot-stars: internal error, the set breaks a rule: " << problems.front() << "\n";
    return 2;
  }
  const fs::path json = out;
  std::error_code ec;
  if (json.has_parent_path()) fs::create_directories(json.parent_path(), ec);
  if (const auto saved = rhot::save_star_set(*set, json); !saved) {
    std::cerr << "rhot-stars: " << saved.error() << "\n";
    return 1;
  }
  const fs::path stem = json.parent_path() / json.stem();
  if (!no_meshes) {
    for (const rhot::MarkerStar& star : set->stars) {
      const fs::path stl = stem.string() + "-star-" + std::to_string(star.id) + ".stl";
      if (!write_stl(stl, star_mesh(star, diameter), std::to_string(star.id))) {
        std::cerr << "rhot-stars: " << stl.string() << ": cannot write\n";
        return 1;
      }
    }
  }
  const fs::path picture = stem.string() + ".svg";
  std::ofstream(picture) << svg(*set);
  std::cout << set->stars.size() << " stars written to " << json.string() << " (picture " << picture.string()
            << (no_meshes ? "" : ", meshes " + stem.string() + "-star-<id>.stl") << ")\n";
  return 0;
}
