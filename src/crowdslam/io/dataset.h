#pragma once
// Image sequences the SLAM system consumes: TUM RGB-D / Bonn, EuRoC MAV, KITTI odometry, a folder of
// images, a video file or a live camera. Everything here is read-only: no reader ever writes to the data.
//
// Design
//   FrameSource  - sequential access, the one interface SLAM iterates: `while (auto f = src.next())`.
//                  Every source implements it, including videos and cameras, which cannot seek.
//   Dataset      - a FrameSource over a fixed list of frames on disk, adding random access
//                  (frame_info(i), load(i)), ground truth and list counts. next() walks load(0..size-1).
//   open_source(spec)   - factory for anything: a directory (layout detected), a video file, or a
//                         camera index ("0", "1", ...).
//   open_dataset(dir)   - factory for directory layouts only (random access guaranteed).
// Layout-specific calibration is on the derived classes (EurocDataset, KittiDataset in their headers).
//
// Errors: missing or malformed inputs throw crowdslam::InputError naming the file (and the line for list
// files). Opening a dataset parses every list and checks that every listed image file exists (a path
// that cannot be checked, e.g. too long or a symlink loop, is "LIST:LINE: PATH: reason"); load(i)
// additionally decodes the images strictly (image_check.h: truncated or corrupt JPEG/PNG are errors),
// checks that depth is 16-bit, that the colour image has the size of the first frame's colour image
// (the message names the colour file and both sizes; not for image folders), and that depth / right
// images have the colour image's size. Paths and list lines quoted in messages are clipped (input_text.h).
//
// Nothing is dropped silently: entries a reader skips (duplicated time stamps, EuRoC left images without
// a right image) are counted and warned about once (spdlog::warn) with the first LIST:LINE; see the
// layout headers for what each layout skips.
//
// Depth is kept raw (CV_16UC1 as stored); Settings::depth_map_factor converts it to metres.
#include <cstddef>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "crowdslam/io/trajectory.h"

namespace crowdslam::io {

enum class SensorKind { kMonocular, kStereo, kRgbd };
// "monocular", "stereo", "rgbd".
std::string to_string(SensorKind sensor);
// Inverse of to_string; throws InputError naming `what` (e.g. the option) for an unknown name.
SensorKind parse_sensor_kind(const std::string& name, const std::string& what);

struct FrameInfo {
  std::size_t index = 0;
  double timestamp_s = 0.0;  // of the colour / left image
  std::string colour_path;   // colour or grey (left for stereo); empty for video/camera frames
  std::string depth_path;    // empty = none
  std::string right_path;    // empty = none
};

struct FrameImages {
  cv::Mat colour;  // as stored: 8-bit BGR or 8-bit grey (left image for stereo)
  cv::Mat depth;   // CV_16UC1 raw values, or empty
  cv::Mat right;   // right image for stereo, or empty
};

struct Frame {
  FrameInfo info;
  FrameImages images;
};

// Everything `crowdslam dataset info` reports. Counts that do not apply are 0.
struct SourceSummary {
  std::string path;
  std::string layout;  // "tum", "euroc", "kitti", "images", "video", "camera"
  SensorKind sensor = SensorKind::kMonocular;
  std::optional<std::size_t> frames;  // frames next() yields; nullopt for cameras
  std::size_t colour_entries = 0;     // colour / left list entries
  std::size_t depth_entries = 0;      // depth list entries (RGB-D)
  std::size_t right_entries = 0;      // right list entries (stereo)
  std::size_t ground_truth_poses = 0;
  std::string ground_truth_path;   // empty = none
  double first_timestamp_s = 0.0;  // of the frames (0 when unknown)
  double last_timestamp_s = 0.0;
  double fps = 0.0;           // nominal rate for images / video / camera, 0 otherwise
  std::string settings_path;  // DIR/settings.yaml when present
};

struct DatasetOptions {
  double fps = 0.0;                     // image folders / videos: frame rate for timestamps; 0 = default
                                        // (video: the file's rate, else 30; image folder: 30)
  double max_time_difference_s = 0.02;  // TUM colour-depth association window
  // A listed image that does not exist is kept as a frame (its load fails, and a run with
  // --skip-bad-frames skips it) instead of failing the open.
  bool missing_images_ok = false;

  void check() const;  // throws InputError naming the bad value
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  FrameSource() = default;
  FrameSource(const FrameSource&) = delete;
  FrameSource& operator=(const FrameSource&) = delete;

  [[nodiscard]] virtual std::string path() const = 0;
  [[nodiscard]] virtual std::string layout() const = 0;
  [[nodiscard]] virtual SensorKind sensor() const = 0;
  // The next frame in order, or nullopt at the end of the stream. Throws InputError for a bad frame.
  virtual std::optional<Frame> next() = 0;
  [[nodiscard]] virtual SourceSummary summary() const = 0;
  // Ground truth (world_from_cam with stamps in seconds); empty when the source has none.
  [[nodiscard]] virtual const Trajectory& ground_truth() const;
  // DIR/settings.yaml when the dataset ships one, else empty.
  [[nodiscard]] virtual std::string default_settings_path() const { return {}; }
};

// What a layout reader hands to Dataset.
struct DatasetContents {
  std::string directory;
  std::string layout;
  SensorKind sensor = SensorKind::kMonocular;
  std::vector<FrameInfo> frames;
  std::size_t colour_entries = 0;
  std::size_t depth_entries = 0;
  std::size_t right_entries = 0;
  Trajectory ground_truth;
  std::string ground_truth_path;
  double fps = 0.0;
  // load() checks every colour image against frame 0's size (a camera's sequence). False for image
  // folders, which may hold photos of any size (vocabulary training); a SLAM run checks sizes itself.
  bool same_size_frames = true;
};

class Dataset : public FrameSource {
 public:
  explicit Dataset(DatasetContents contents);

  [[nodiscard]] std::string path() const override { return contents_.directory; }
  [[nodiscard]] std::string layout() const override { return contents_.layout; }
  [[nodiscard]] SensorKind sensor() const override { return contents_.sensor; }
  [[nodiscard]] std::size_t size() const { return contents_.frames.size(); }
  [[nodiscard]] const FrameInfo& frame_info(std::size_t index) const { return contents_.frames.at(index); }
  [[nodiscard]] const std::vector<FrameInfo>& frames() const { return contents_.frames; }
  // Reads and validates frame `index` (see the header comment). Thread-safe. The colour size of frame 0
  // is the reference every other frame is checked against (read once, when frame 0 is loaded or, for
  // random access, when first needed).
  [[nodiscard]] FrameImages load(std::size_t index) const;

  std::optional<Frame> next() override;
  void rewind(std::size_t index = 0) { cursor_ = index; }

  [[nodiscard]] const Trajectory& ground_truth() const override { return contents_.ground_truth; }
  [[nodiscard]] SourceSummary summary() const override;
  [[nodiscard]] std::string default_settings_path() const override;

 private:
  // Size of frame 0's colour image, or nullopt when it cannot be read (no check then).
  [[nodiscard]] std::optional<cv::Size> reference_size(std::size_t index, const cv::Mat& colour) const;

  DatasetContents contents_;
  std::size_t cursor_ = 0;
  mutable std::mutex reference_mutex_;
  mutable std::optional<cv::Size> reference_size_;
  mutable bool reference_known_ = false;  // reference_size_ was determined (possibly as unreadable)
};

// Directory layouts, detected from the files present (see the layout headers):
//   rgb.txt -> TUM/Bonn; mav0/cam0/data.csv (or cam0/data.csv in a mav0 folder) -> EuRoC;
//   times.txt + image_0/ -> KITTI; otherwise image files -> image folder.
// Throws InputError naming `directory` when it is missing or no layout matches.
std::unique_ptr<Dataset> open_dataset(const std::string& directory, const DatasetOptions& options = {});

// A directory (open_dataset), a video file, or a camera index ("0"). Throws InputError naming `spec`;
// a list or other text file (DIR/rgb.txt, data.csv, settings.yaml, *.json, ...) is refused with a
// message saying so and asking for the dataset directory (its parent) instead of being opened as a video.
std::unique_ptr<FrameSource> open_source(const std::string& spec, const DatasetOptions& options = {});

}  // namespace crowdslam::io
