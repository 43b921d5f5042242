#pragma once
// Ray-casting renderer: one ray per pixel centre against the room, the obstacles and the people; exact
// z-depth, trilinear texture lookup, a constant Lambertian shade per face. People are boxes, or, with
// person sprites, billboards (billboard.h) whose sprite is alpha-tested: a ray through a transparent
// texel passes on, so people occlude each other and the room only where the photograph shows the person.
// Pure function of its inputs (no noise), so the same frame renders to the same bytes every time.
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "crowdslam/synth/billboard.h"
#include "crowdslam/synth/scene.h"

namespace crowdslam::synth {

struct RenderedFrame {
  cv::Mat colour;        // CV_8UC3, BGR
  cv::Mat depth_m;       // CV_32F z-depth in metres (0 = nothing hit)
  cv::Mat person_label;  // CV_16U id of the person seen at the pixel (0 = static scene or a mover)
  cv::Mat moving;        // CV_8U 255 where the pixel shows something that moves (a person or a mover), else 0
};

// Renders the static scene plus the moving boxes (people and movers) and the people's billboards (their
// sprites are scene.sprites()) seen by a camera at world_from_cam.
RenderedFrame render(const Scene& scene, const geometry::SE3& world_from_cam, const std::vector<Box>& moving,
                     const std::vector<Billboard>& billboards = {});
// Frame `frame` of the sequence from the left (RGB) or right stereo camera.
RenderedFrame render_frame(const Scene& scene, int frame, bool right_camera = false);

// The pixels one billboard covers with nothing in front of it: its opaque pixels in the image when rendered
// alone, counted with the very test render() uses (so a pixel labelled with the person in a render is one
// of them), and their extent in pixel indices (max < min when there are none). `unbounded_pixels` also
// counts the pixels beyond the image borders it would cover on a larger sensor of the same camera (exact
// up to 600 px of projection, sampled on a coarser grid beyond), so that visible / unbounded_pixels is
// MOT's visibility: occlusion and image border cropping.
struct BillboardFootprint {
  int pixels = 0;
  double unbounded_pixels = 0.0;
  int min_u = 0, min_v = 0, max_u = -1, max_v = -1;
};
BillboardFootprint billboard_footprint(const Scene& scene, const Billboard& billboard,
                                       const geometry::SE3& world_from_cam);

// Bounding rectangle of the projection of the part of `box` in front of the camera, in 0-based pixel
// coordinates (pixel centres at integers), clipped to [0, width-1] x [0, height-1]; nullopt when no part
// of it projects into the image. Rectangle = (x, y, width, height) with x + width = right edge.
std::optional<cv::Rect2d> projected_bounds(const Box& box, const geometry::SE3& cam_from_world,
                                           const Intrinsics& intrinsics);

}  // namespace crowdslam::synth
