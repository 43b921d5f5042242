#pragma once
// Writes a complete synthetic dataset.
//
// RGB-D (default), TUM layout: rgb/NNNNNN.png, depth/NNNNNN.png (16-bit, depth_m * 5000, 0 = missing),
// rgb.txt, depth.txt, groundtruth.txt (TUM), settings.yaml (ORB-SLAM2 style), people_gt.txt, synth.json.
// Stereo (--stereo), KITTI odometry layout: image_0/ and image_1/ (BGR PNG), times.txt, calib.txt,
// poses.txt (KITTI), plus groundtruth.txt, settings.yaml, people_gt.txt, synth.json.
//
// With --movers K: mask/NNNNNN.png (8-bit, same name as the image) is 255 where the left/RGB image shows
// something that moves (a person or a mover) and 0 elsewhere; synth.json lists the movers.
//
// people_gt.txt is MOT style, one line per person visible in a frame (at least one pixel). Box people:
//   frame(1-based),id,x,y,w,h,1,-1,-1,-1
// where (x, y, w, h) is the bounding rectangle of the projection of the person's 3D box in 0-based pixel
// coordinates (pixel centres at integers, as OpenCV), clipped to the image.
// Billboard people (person sprites), MOT16/17 ground truth with class 1 (pedestrian) and visibility:
//   frame(1-based),id,x,y,w,h,1,1,visibility
// where (x, y, w, h) spans the person's opaque sprite pixels whether hidden or not (pixel edges: x = leftmost
// pixel - 0.5, x + w = rightmost pixel + 0.5), clipped to [0, width-1] x [0, height-1], and visibility =
// the person's pixels in the image / the pixels it would cover with nothing in front and no image border
// (render.h: billboard_footprint), as MOT16/17 (occlusion and border cropping). With billboard people,
// people_mask/NNNNNN.png (16-bit) holds the person id at each pixel showing a person and 0 elsewhere;
// synth.json says "people_model": "sprites" (else "boxes"), "person_mask": "people_mask".
//
// The output appears atomically: everything is written into "<out_dir>.tmp-<pid>" which is renamed to
// out_dir at the end; an existing non-empty out_dir is an error unless options.force.
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "crowdslam/synth/render.h"
#include "crowdslam/synth/scene.h"

namespace crowdslam::synth {

struct SequenceSummary {
  int frames = 0;
  int person_boxes = 0;         // lines in people_gt.txt
  double min_person_distance_m = 0.0;  // closest any person's body came to the camera centre (inf: none)
  double max_person_coverage = 0.0;    // largest fraction of an image covered by people
  double seconds = 0.0;
  bool photo_textures = false;
  bool sprite_people = false;  // billboards with person sprites (else textured boxes)
  std::string crowd;           // the crowd profile used
};

// `on_frame(done, total)` (optional) is called after each written frame, from the rendering threads one
// at a time, with the number of frames finished so far.
using FrameProgress = std::function<void(int done, int total)>;
SequenceSummary write_sequence(const SynthOptions& options, const std::filesystem::path& out_dir,
                               const FrameProgress& on_frame = {});

// The MOT lines (without frame-independent parts) for one rendered frame: visible people and their boxes.
struct PersonBox {
  int id = 0;
  cv::Rect2d box;
  double visibility = -1.0;       // billboard people: visible / unoccluded pixels; -1 for box people
  int visible_pixels = 0;         // billboard people: pixels labelled with the person
  int pixels = 0;                 // billboard people: pixels of the image it covers with nothing in front
  double unbounded_pixels = 0.0;  // ... and beyond the image borders
};
// Box people: boxes from the 3D boxes; billboard people: from the footprints, with visibility.
std::vector<PersonBox> visible_person_boxes(const Scene& scene, const RenderedFrame& rendered,
                                            const geometry::SE3& world_from_cam, int frame);

// settings.yaml content for the options (ORB-SLAM2 style).
std::string settings_yaml(const SynthOptions& options);

}  // namespace crowdslam::synth
