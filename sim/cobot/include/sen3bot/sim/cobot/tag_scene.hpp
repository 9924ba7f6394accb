#pragma once
// Simulated camera frames of operators showing their tags, for the simulator and the tests:
// what the robot's camera would see of a leg band's tag in a plant, through the robot's own
// camera calibration (nav::CameraProjection), with perspective, blur, noise and lighting.
//
// The scene: a wall straight ahead and the floor up to it, textured (tiles, panel seams, a
// safety stripe, shelves, uneven light, fixed-pattern noise), all drawn once at init(). Per
// frame: each operator's legs as dark quads, each tag as its 3D square projected by a
// homography, then lighting, motion and defocus blur and per-pixel noise.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "sen3bot/camera/frame_pool.hpp"
#include "sen3bot/cobot/tag.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/people.hpp"

namespace sen3bot::cobot {

// One tag in the scene, in the laser's frame (forward, left; up above the scan plane).
struct SceneTag {
  double forward_m = 0.75;
  double left_m = 0.0;
  // The leg band's tag centre is 0.35 m above the floor and the scan plane 0.3 m: 0.05.
  double up_m = 0.05;
  // The tag's turn away from the camera about the vertical: 0 faces it squarely, positive turns
  // the tag's left edge away (counter-clockwise seen from above). Beyond kReadableFacingRad the
  // code is drawn blank (seen too obliquely to read); beyond pi/2 only the leg is seen.
  double facing_rad = 0.0;
  Tag tag;
  double side_m = 0.10;  // the code's side, without its white quiet zone (4 modules each side)
};

struct SceneOptions {
  double laser_height_m = 0.3;    // the scan plane above the floor (sim::SimDetectorConfig's)
  double wall_distance_m = 4.0;   // the wall ahead, from the laser
  bool body = true;               // draw the operator's legs and trousers behind each tag
  double defocus_sigma_px = 0.7;  // Gaussian blur of the whole frame (focus, optics)
  double motion_blur_px = 0.0;    // horizontal smear (the robot turning, the operator moving); < 1: none
  double noise_sigma = 4.0;       // per-pixel Gaussian noise, grey levels, new every frame
  double gain = 1.0;              // lighting: each pixel becomes gain * value + offset
  double offset = 0.0;
  // Another QR code of the plant on the wall (a rack's label), 0.5 m left of straight ahead at
  // the laser's height; empty: none. It is no tag and the reader must refuse it.
  std::string wall_code;
  double wall_code_side_m = 0.30;
};

class TagSceneRenderer {
 public:
  // Tags farther than this from straight facing are drawn without their code.
  static constexpr double kReadableFacingRad = 70.0 * 3.14159265358979323846 / 180.0;
  static constexpr std::size_t kMaxTags = 8;

  TagSceneRenderer();
  ~TagSceneRenderer();
  TagSceneRenderer(const TagSceneRenderer&) = delete;
  TagSceneRenderer& operator=(const TagSceneRenderer&) = delete;

  // Checks the options, allocates the frame and its scratch at the calibration's image size
  // and draws the background from the seed. The n-th render() after init() gives the same
  // pixels for the same seed, options and tags.
  Status init(const nav::CameraCalibration& calibration, std::uint64_t seed, const SceneOptions& options = {});

  // One frame with the tags (at most kMaxTags; nearest drawn last) into pixels: rows of
  // stride_bytes, bgr8 or gray8, the calibration's width x height. False, with nothing
  // written, when the buffer is too small, there are too many tags, a tag's payload cannot be
  // encoded, or init() did not succeed.
  bool render(std::span<const SceneTag> tags, std::span<std::uint8_t> pixels, std::uint32_t stride_bytes,
              camera::PixelFormat format);

  // Where a tag's centre falls in the frame (false: behind the camera), for the tests' ROI.
  bool centre_px(const SceneTag& tag, double& u_px, double& v_px) const noexcept;
  // True when the whole tag with its quiet zone falls inside the frame (as turned).
  [[nodiscard]] bool in_view(const SceneTag& tag) const noexcept;
  [[nodiscard]] std::uint32_t width_px() const noexcept { return width_px_; }
  [[nodiscard]] std::uint32_t height_px() const noexcept { return height_px_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::uint32_t width_px_ = 0;
  std::uint32_t height_px_ = 0;
};

}  // namespace sen3bot::cobot
