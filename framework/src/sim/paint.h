// Procedural materials and decals of the simulated room (internal to the simulator).
//
// A face is painted by a FacePaint: a material covering the whole face plus decals (posters, doors,
// windows, ...) on rectangles of it. albedo(s, t) takes face coordinates in metres (t is height on
// walls) and is deterministic in the seeds: textures are painted texel by texel in parallel.
// Scales are chosen so that a direct method finds gradients everywhere: millimetre grain, centimetre
// patterns and decimetre-to-metre structure, like an office or lab.
#pragma once
#include <cstdint>
#include <vector>

namespace rsvio::sim::paint {

enum class Material { Plaster, Wallpaper, FloorPlanks, CeilingTiles, Wood, DarkWood, Fabric, Cardboard, Books, Plain, Leaves };

enum class DecalKind {
  Poster, Frame, Door, Window, Whiteboard, Baseboard, Switch, Lamp, Rug, CabinetDoors, Drawers, Clock, Tape
};

struct Decal {
  DecalKind kind = DecalKind::Poster;
  double s0 = 0, t0 = 0, s1 = 0, t1 = 0;  // rectangle on the face, metres
  uint64_t seed = 0;
  int variant = 0;
  double tone = 0.5;
};

struct Shade {
  double albedo = 0.0;
  double emission = 0.0;  // added after lighting (lamps, the sky behind a window)
};

struct FacePaint {
  Material material = Material::Plain;
  uint64_t seed = 0;
  double tone = 0.6;          // base albedo
  bool along_t = false;       // grain/planks/books run along t instead of s
  std::vector<Decal> decals;  // later decals cover earlier ones
};

Shade shade(const FacePaint& fp, double s, double t);

}  // namespace rsvio::sim::paint
