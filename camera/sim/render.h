// Ray caster of simulator primitives (round cones, ellipsoids, quads, cone shells) into a
// RenderedFrame: linear intensity with Lambertian shading, the human mask after occlusion
// and camera-z depth.
//
// Pixel convention: pixel (x, y) is centred on image coordinates (x, y) (OpenCV), so the
// ray of pixel (x, y) in the camera frame is ((x - cx) / fx, (y - cy) / fy, 1) and a hit's
// ray parameter is its camera z. Depth and mask come from that centre ray; intensity is
// anti-aliased: texture patterns are box-filtered over the pixel footprint (ray
// differentials) and pixels on a silhouette or a primitive boundary are supersampled, so an
// edge or a stripe moving by a fraction of a pixel changes intensity by that fraction, not
// by a whole step (a step would be a burst of fake events).
//
// Speed: each primitive's screen rectangle (exact projection of its bounding spheres or
// corners) is binned into 16x16 tiles; only tiles some primitive touches are cast, and each
// tile's list is sorted by nearest possible depth so a ray stops early. A Renderer can
// cache a static layer (walls, floor, fixed occluders) once and composite the moving
// primitives onto it each frame, re-casting only the tiles they touch. Rows are split over
// OpenMP threads; every pixel is a pure function of its inputs, so the output is
// bit-identical for any thread count.
#pragma once
#include <memory>
#include <vector>

#include "camera/sim/types.h"

namespace yelan::camera::sim {

// Illumination: a directional key light plus ambient, both scaled by one level and
// modulated by lamp flicker. An albedo-1 surface facing the key light gets `level`
// (times the flicker factor); a surface facing away gets `level * ambient`.
struct Lighting {
  double level = 255;                       // intensity of white facing the key light
  Vec3 key_dir = Vec3(0.3, -0.6, 0.74);     // world direction TOWARDS the key light
  double ambient = 0.35;                    // fraction of level reaching every surface
  double flicker_depth = 0;                 // modulation depth m: factor 1 + m cos(2 pi f t)
  double flicker_hz = 100;                  // mains 50 Hz -> 100 Hz intensity ripple
  // The factor every intensity is multiplied by at time t (mean 1 over a period).
  double flicker(double t_s) const;
};

struct RenderOptions {
  int edge_samples = 8;  // rays per boundary pixel: 1 (no edge AA), 4, 8 or 16
  int threads = 0;       // OpenMP threads; 0: the OpenMP default (omp_get_max_threads)
};

// Renders `prims` from scratch (no cached layer). Pixels no primitive covers get
// intensity 0, mask 0, depth +inf. Throws std::invalid_argument on an unusable camera.
void render(const CameraModel& cam, const std::vector<Primitive>& prims, const Lighting& light,
            double t_s, RenderedFrame& out, const RenderOptions& options = {});

// Keeps a rendered static layer and composites moving primitives onto it. Holds all
// scratch buffers, so rendering a frame allocates nothing once sizes are stable.
class Renderer {
 public:
  explicit Renderer(RenderOptions options = {});
  ~Renderer();
  Renderer(Renderer&&) noexcept;
  Renderer& operator=(Renderer&&) noexcept;

  // Renders `static_prims` once (without flicker) as the layer every later frame starts
  // from. Call again when the camera, the lighting or the static primitives change.
  void set_static(const CameraModel& cam, const std::vector<Primitive>& static_prims,
                  const Lighting& light);
  // The static layer plus `dynamic_prims` at time t_s (flicker applied to everything).
  // Same mask and depth as render(cam, static + dynamic, ...); intensities match too, except
  // on the boundary pixels of moving primitives over a flat part of the layer, whose rays
  // that miss the moving primitives take the layer's pixel average instead of being shaded
  // one by one (a difference within the texture's variation inside one pixel).
  void render(double t_s, const std::vector<Primitive>& dynamic_prims, RenderedFrame& out);
  // The same without flicker: the caller applies Lighting::flicker itself (the simulator
  // does, per pixel step, so flicker does not force keyframes at the pixel rate).
  void render_unflickered(const std::vector<Primitive>& dynamic_prims, RenderedFrame& out);

  const CameraModel& camera() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace yelan::camera::sim
