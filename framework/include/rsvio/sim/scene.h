// The simulated world: a closed room (an inside-out axis-aligned box) holding axis-aligned boxes
// (furniture), every face textured with baked radiance.
//
// Contract
// - World frame z up, metres. Solid 0 is the room, seen from inside; the others are boxes seen from
//   outside. Faces are numbered 2 * axis + side (side 0 at the min bound, 1 at the max bound).
// - A face's texture coordinates (s, t) are its two other world coordinates, in axis order, minus the
//   solid's min corner: x-faces (y, z), y-faces (x, z), z-faces (x, y).
// - Radiance is Lambertian and static (view-independent, baked into the textures), so a point looks
//   the same from every pose: the brightness-constancy assumption of direct methods holds exactly
//   unless an effect breaks it on purpose.
// - defaultRoom() builds the standard indoor scene from the "scene" stream of the seed: the same seed
//   and scene parameters give the same room whatever else the config says.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "rsvio/core/types.h"
#include "rsvio/sim/texture.h"

namespace rsvio::sim {

struct SceneSpec {
  Vec3 room_size_m = Vec3(9.0, 7.0, 3.0);  // x, y, z extents; the room spans [-x/2, x/2] x [-y/2, y/2] x [0, z]
  int furniture = 16;                      // boxes along the walls (plus one table in the middle)
  double texel_mm = 4.0;                   // texture resolution on walls, floor and furniture
  double brightness = 1.0;                 // scales the lighting
  bool table = true;                       // a table in the middle of the room
};

class Scene {
 public:
  struct Hit {
    double t = 0.0;  // ray parameter (distance for a unit direction)
    int solid = -1;
    int face = -1;
    Vec3 p = Vec3::Zero();
  };

  int addTexture(TextureMap tex);
  // textures: per face, an index returned by addTexture. Solid 0 must be the room (inside_out).
  int addSolid(const Vec3& min, const Vec3& max, const std::array<int, 6>& textures, bool inside_out);

  // Nearest hit with t > 1e-9 along o + t d (d need not be unit). False when nothing is hit.
  bool intersect(const Vec3& o, const Vec3& d, Hit& hit) const;
  // The same, testing only the room and the boxes listed in `solids` (a caller's conservative cull).
  bool intersect(const Vec3& o, const Vec3& d, Hit& hit, const int* solids, int n) const;
  float radiance(const Hit& hit, double footprint_m) const;
  Vec3 normal(const Hit& hit) const;  // unit normal facing into the free space

  int numSolids() const { return static_cast<int>(solids_.size()); }
  Vec3 solidMin(int i) const { return solids_[i].min; }
  Vec3 solidMax(int i) const { return solids_[i].max; }
  size_t textureBytes() const;
  TextureMap& mutableTexture(int i) { return textures_[i]; }  // for painters, before rendering starts

  // The standard room (scene_room.cpp). Textures are painted with up to `threads` threads; the
  // result does not depend on the thread count.
  static Scene defaultRoom(const SceneSpec& spec, uint64_t seed, int threads);

 private:
  struct Solid {
    Vec3 min, max;
    std::array<int, 6> tex;
    bool inside_out = false;
  };
  std::vector<Solid> solids_;
  std::vector<TextureMap> textures_;
};

}  // namespace rsvio::sim
