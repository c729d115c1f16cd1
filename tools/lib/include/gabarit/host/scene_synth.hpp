// Grayscale test sequences for 4-DOF tracking (the microscope case of the
// thesis, section 6.1), built from real photographs of Debian's
// python3-skimage at run time:
//   - the object: a five-lobed cog cut from `camera.png` (the cameraman), 2x
//     downscaled (its outline shows its orientation);
//   - the background: a cluttered real texture (`gravel.png`);
//   - a smooth known trajectory in x, y and theta (sums of slow sines), and a
//     depth that walks through the focus stack;
//   - a slow illumination change (gain and offset), Gaussian sensor noise,
//     motion blur on a few frames, and an occlusion of `occlusion_frames`
//     frames by a patch of another photograph (`brick.png`);
//   - a focus stack: the object is *tilted*, so at depth n its blur grows with
//     the distance of each column from the column in focus, which moves across
//     the object with n. No two depths look alike.
// Outputs frames.y4m, gt.csv (frame,x,y,theta_deg,depth,visible) and the model
// stack model_NN.pgm (the object at theta 0 on mid-grey, one per depth, the
// reference point at the image centre). Same options, same bytes.
#pragma once

#include <cstdint>
#include <string>

namespace gabarit::host {

struct SceneOptions {
  std::uint32_t frames = 240;
  std::uint32_t width = 384;
  std::uint32_t height = 288;
  std::uint16_t depths = 1;              // focus-stack images (1: no depth change)
  double max_speed_px = 2.5;             // largest per-frame translation of the trajectory
  double max_turn_deg = 1.0;             // largest per-frame rotation
  double noise_sigma = 3.0;              // grey levels
  double illumination = 0.2;             // gain swings between 1 - this and 1 + this
  std::uint32_t occlusion_start = 100;   // first occluded frame (0 frames: none)
  std::uint32_t occlusion_frames = 18;
  std::uint32_t blur_every = 50;         // a motion-blurred frame every N frames (0: none)
  std::uint64_t seed = 1;
};

struct SceneSummary {
  std::uint32_t object_radius = 0;
  std::uint32_t visible_frames = 0;
};

SceneSummary write_scene_sequence(const SceneOptions& options, const std::string& dir);

}  // namespace gabarit::host
