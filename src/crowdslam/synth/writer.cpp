#include "crowdslam/synth/writer.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <thread>

#include "crowdslam/io/opencv_extras.h"
#include "crowdslam/io/trajectory.h"
#include "crowdslam/util/atomic_file.h"
#include "crowdslam/util/interrupt.h"
#include "crowdslam/util/error.h"

namespace crowdslam::synth {
namespace fs = std::filesystem;
namespace {

std::string format(const char* fmt, double a) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, fmt, a);
  return buffer;
}

std::string frame_name(int frame) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%06d.png", frame);
  return buffer;
}

// Fast PNG settings: zlib level 1; RLE for colour (photographs barely compress better, encode 25% faster).
void write_png(const fs::path& path, const cv::Mat& image) {
  bool ok = false;
  const int strategy = image.channels() == 3 ? cv::IMWRITE_PNG_STRATEGY_RLE : cv::IMWRITE_PNG_STRATEGY_DEFAULT;
  try {
    ok = io::opencv_extras().imwrite(path.string(), image,
                                     {cv::IMWRITE_PNG_COMPRESSION, 1, cv::IMWRITE_PNG_STRATEGY, strategy});
  } catch (const cv::Exception& e) {
    throw input_error(path.string(), std::string("cannot write image: ") + e.what());
  }
  if (!ok) throw input_error(path.string(), "cannot write image");
}

cv::Mat depth_png(const cv::Mat& depth_m, double noise_sigma_m, Rng rng) {
  cv::Mat out(depth_m.size(), CV_16U);
  for (int y = 0; y < depth_m.rows; ++y) {
    const float* in = depth_m.ptr<float>(y);
    auto* o = out.ptr<std::uint16_t>(y);
    for (int x = 0; x < depth_m.cols; ++x) {
      double d = in[x];
      if (d > 0.0 && noise_sigma_m > 0.0) d += noise_sigma_m * rng.normal();
      o[x] = (d > 0.0 && d <= kMaxDepthM) ? static_cast<std::uint16_t>(std::lround(d * kDepthFactor)) : 0;
    }
  }
  return out;
}

// What one frame contributes to the text files and the summary.
struct FrameResult {
  std::vector<PersonBox> boxes;
  double coverage = 0.0;
};

void prepare_output(const SynthOptions& options, const fs::path& out_dir) {
  std::error_code ec;
  if (fs::exists(out_dir, ec)) {
    if (!fs::is_directory(out_dir, ec)) throw input_error(out_dir.string(), "exists and is not a directory");
    if (!fs::is_empty(out_dir, ec) && !options.force) {
      throw input_error(out_dir.string(), "output directory exists and is not empty (use --force to replace it)");
    }
  }
}

class SequenceWriter {
 public:
  SequenceWriter(const Scene& scene, fs::path dir, const FrameProgress& on_frame)
      : scene_(scene), dir_(std::move(dir)), on_frame_(on_frame) {}

  std::vector<FrameResult> write_frames() {
    const SynthOptions& o = scene_.options();
    const bool stereo = o.stereo;
    fs::create_directories(dir_ / (stereo ? "image_0" : "rgb"));
    fs::create_directories(dir_ / (stereo ? "image_1" : "depth"));
    if (o.movers > 0) fs::create_directories(dir_ / "mask");
    if (scene_.sprite_people()) fs::create_directories(dir_ / "people_mask");
    results_.assign(scene_.frame_count(), {});
    const int threads = std::max(1, std::min(8, static_cast<int>(std::thread::hardware_concurrency())));
    std::vector<std::thread> pool;
    for (int i = 0; i < threads; ++i) pool.emplace_back([this] { work(); });
    for (auto& t : pool) t.join();
    if (error_) std::rethrow_exception(error_);
    return std::move(results_);
  }

 private:
  void work() {
    while (!failed_) {
      const int frame = next_++;
      if (frame >= scene_.frame_count()) return;
      try {
        throw_if_interrupted();  // `crowdslam synth` inside an InterruptScope
        write_frame(frame);
        if (on_frame_) {
          const std::lock_guard<std::mutex> lock(mutex_);
          on_frame_(++done_, scene_.frame_count());
        }
      } catch (...) {
        const std::lock_guard<std::mutex> lock(mutex_);
        if (!error_) error_ = std::current_exception();
        failed_ = true;
      }
    }
  }

  void write_frame(int frame) {
    const SynthOptions& o = scene_.options();
    const std::string name = frame_name(frame);
    const geometry::SE3& world_from_cam = scene_.trajectory()[frame].world_from_cam;
    const std::vector<Box> people = scene_.moving_boxes(frame);
    const std::vector<Billboard> billboards = scene_.people_billboards(frame);  // facing the left camera
    const RenderedFrame left = render(scene_, world_from_cam, people, billboards);
    if (o.stereo) {
      write_png(dir_ / "image_0" / name, left.colour);
      write_png(dir_ / "image_1" / name,
                render(scene_, scene_.right_world_from_cam(frame), people, billboards).colour);
    } else {
      write_png(dir_ / "rgb" / name, left.colour);
      write_png(dir_ / "depth" / name, depth_png(left.depth_m, o.noise_depth_m, Rng(o.seed, 0xde97ULL + frame)));
    }
    if (o.movers > 0) write_png(dir_ / "mask" / name, left.moving);
    if (scene_.sprite_people()) write_png(dir_ / "people_mask" / name, left.person_label);
    FrameResult& result = results_[frame];
    result.boxes = visible_person_boxes(scene_, left, world_from_cam, frame);
    result.coverage = static_cast<double>(cv::countNonZero(left.person_label)) / left.person_label.total();
  }

  const Scene& scene_;
  fs::path dir_;
  const FrameProgress& on_frame_;
  int done_ = 0;  // frames written (under mutex_)
  std::vector<FrameResult> results_;
  std::atomic<int> next_{0};
  std::atomic<bool> failed_{false};
  std::mutex mutex_;
  std::exception_ptr error_;
};

std::string image_list(const Scene& scene, const std::string& folder, const std::string& what) {
  std::ostringstream out;
  out << "# " << what << "\n# file: 'crowdslam synth'\n# timestamp filename\n";
  for (int i = 0; i < scene.frame_count(); ++i) {
    out << format("%.6f", scene.trajectory()[i].timestamp_s) << ' ' << folder << '/' << frame_name(i) << '\n';
  }
  return out.str();
}

std::string calib_txt(const Intrinsics& k) {
  const auto row = [&k](const std::string& name, double tx) {
    std::ostringstream out;
    out << name << ':';
    const double values[12] = {k.fx, 0, k.cx, tx, 0, k.fy, k.cy, 0, 0, 0, 1, 0};
    for (double v : values) out << ' ' << format("%.12e", v);
    out << '\n';
    return out.str();
  };
  const double right_tx = -k.fx * kStereoBaselineM;
  return row("P0", 0.0) + row("P1", right_tx) + row("P2", 0.0) + row("P3", right_tx);
}

std::string people_gt(const std::vector<FrameResult>& results, bool with_visibility) {
  std::ostringstream out;
  char line[160];
  for (size_t f = 0; f < results.size(); ++f) {
    for (const PersonBox& p : results[f].boxes) {
      if (with_visibility) {
        std::snprintf(line, sizeof line, "%zu,%d,%.2f,%.2f,%.2f,%.2f,1,1,%.4f\n", f + 1, p.id, p.box.x,
                      p.box.y, p.box.width, p.box.height, p.visibility);
      } else {
        std::snprintf(line, sizeof line, "%zu,%d,%.2f,%.2f,%.2f,%.2f,1,-1,-1,-1\n", f + 1, p.id, p.box.x,
                      p.box.y, p.box.width, p.box.height);
      }
      out << line;
    }
  }
  return out.str();
}

SequenceSummary summarise(const Scene& scene, const std::vector<FrameResult>& results) {
  SequenceSummary s;
  s.frames = scene.frame_count();
  s.photo_textures = scene.photo_textures();
  s.sprite_people = scene.sprite_people();
  s.crowd = to_string(scene.crowd());
  s.min_person_distance_m = std::numeric_limits<double>::infinity();
  for (const FrameResult& r : results) {
    s.person_boxes += static_cast<int>(r.boxes.size());
    s.max_person_coverage = std::max(s.max_person_coverage, r.coverage);
  }
  for (const PersonTrack& track : scene.people()) {
    for (int f = 0; f < scene.frame_count(); ++f) {
      const Eigen::Vector2d centre = scene.trajectory()[f].world_from_cam.translation().head<2>();
      s.min_person_distance_m = std::min(s.min_person_distance_m, distance_to_person(track.states[f], centre));
    }
  }
  return s;
}

nlohmann::json synth_json(const Scene& scene, const SequenceSummary& summary) {
  const SynthOptions& o = scene.options();
  const Intrinsics& k = scene.intrinsics();
  nlohmann::json j;
  j["generator"] = kGeneratorVersion;
  j["seed"] = o.seed;
  j["frames"] = o.frames;
  j["people"] = o.people;
  j["people_hidden"] = o.hide_people;
  j["movers"] = nlohmann::json::array();
  for (const Mover& m : scene.movers()) j["movers"].push_back({{"id", m.id}, {"kind", to_string(m.kind)}});
  if (!scene.movers().empty()) j["moving_mask"] = "mask";  // mask/NNNNNN.png: 255 = a person or a mover
  j["stereo"] = o.stereo;
  j["layout"] = o.stereo ? "kitti" : "tum";
  j["trajectory"] = to_string(o.trajectory);
  j["width"] = o.width;
  j["height"] = o.height;
  j["noise_depth_m"] = o.noise_depth_m;
  j["fps"] = kFps;
  j["first_timestamp_s"] = kFirstTimestampS;
  j["depth_factor"] = kDepthFactor;
  j["max_depth_m"] = kMaxDepthM;
  j["baseline_m"] = o.stereo ? kStereoBaselineM : 0.0;
  j["intrinsics"] = {{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy}};
  j["textures"] = scene.photo_textures() ? "photos" : "procedural";
  j["crowd"] = to_string(scene.crowd());
  j["room_scale"] = o.room_scale();
  if (scene.sprite_people()) {
    j["people_model"] = "sprites";
    j["sprites"] = o.sprite_dir;
    j["person_mask"] = "people_mask";  // people_mask/NNNNNN.png: 16-bit person id, 0 = no person
    j["people_gt"] = "frame,id,x,y,w,h,1,1,visibility";
  } else {
    j["people_model"] = "boxes";
    j["people_gt"] = "frame,id,x,y,w,h,1,-1,-1,-1";
  }
  if (scene.blackout_frames().first >= 0) {
    j["blackout_frames"] = {scene.blackout_frames().first, scene.blackout_frames().second};
  }
  j["persons"] = nlohmann::json::array();
  for (size_t i = 0; i < scene.people().size(); ++i) {
    const PersonTrack& t = scene.people()[i];
    nlohmann::json person{{"id", t.id}, {"role", to_string(t.role)}};
    if (scene.sprite_people()) {
      person["sprite"] = scene.sprites()[scene.person_sprite(static_cast<int>(i))].record.file;
      person["height_m"] = scene.person_height_m(static_cast<int>(i));
    }
    j["persons"].push_back(person);
  }
  j["person_boxes"] = summary.person_boxes;
  j["max_person_coverage"] = summary.max_person_coverage;
  if (std::isfinite(summary.min_person_distance_m)) j["min_person_distance_m"] = summary.min_person_distance_m;
  return j;
}

void write_text_files(const Scene& scene, const fs::path& dir, const std::vector<FrameResult>& results,
                      const SequenceSummary& summary) {
  const SynthOptions& o = scene.options();
  if (o.stereo) {
    std::ostringstream times;
    for (const auto& pose : scene.trajectory()) times << format("%.6e", pose.timestamp_s) << '\n';
    write_file_atomic(dir / "times.txt", times.str());
    write_file_atomic(dir / "calib.txt", calib_txt(scene.intrinsics()));
    io::write_kitti_trajectory((dir / "poses.txt").string(), scene.trajectory());
  } else {
    write_file_atomic(dir / "rgb.txt", image_list(scene, "rgb", "color images"));
    write_file_atomic(dir / "depth.txt", image_list(scene, "depth", "depth maps"));
  }
  io::write_tum_trajectory((dir / "groundtruth.txt").string(), scene.trajectory());
  write_file_atomic(dir / "settings.yaml", settings_yaml(o));
  write_file_atomic(dir / "people_gt.txt", people_gt(results, scene.sprite_people()));
  write_file_atomic(dir / "synth.json", synth_json(scene, summary).dump(2) + "\n");
}

}  // namespace

namespace {

std::vector<PersonBox> billboard_person_boxes(const Scene& scene, const RenderedFrame& rendered,
                                              const geometry::SE3& world_from_cam, int frame) {
  const int count = static_cast<int>(scene.people().size());
  std::vector<int> visible(count + 1, 0);
  for (int y = 0; y < rendered.person_label.rows; ++y) {
    const auto* row = rendered.person_label.ptr<std::uint16_t>(y);
    for (int x = 0; x < rendered.person_label.cols; ++x) {
      if (row[x] > 0 && row[x] <= count) ++visible[row[x]];
    }
  }
  const Intrinsics& k = scene.intrinsics();
  std::vector<PersonBox> boxes;
  for (const Billboard& b : scene.people_billboards(frame)) {
    if (visible[b.person_id] == 0) continue;
    const BillboardFootprint f = billboard_footprint(scene, b, world_from_cam);
    if (f.pixels == 0) continue;  // cannot happen: every visible pixel is one of the footprint's
    const double x0 = std::max(0.0, f.min_u - 0.5);
    const double y0 = std::max(0.0, f.min_v - 0.5);
    const double x1 = std::min(k.width - 1.0, f.max_u + 0.5);
    const double y1 = std::min(k.height - 1.0, f.max_v + 0.5);
    PersonBox p;
    p.id = b.person_id;
    p.box = cv::Rect2d(x0, y0, x1 - x0, y1 - y0);
    p.visible_pixels = visible[b.person_id];
    p.pixels = f.pixels;
    p.unbounded_pixels = f.unbounded_pixels;
    p.visibility = std::min(1.0, p.visible_pixels / f.unbounded_pixels);
    boxes.push_back(p);
  }
  return boxes;
}

}  // namespace

std::vector<PersonBox> visible_person_boxes(const Scene& scene, const RenderedFrame& rendered,
                                            const geometry::SE3& world_from_cam, int frame) {
  if (scene.sprite_people()) return billboard_person_boxes(scene, rendered, world_from_cam, frame);
  const int count = static_cast<int>(scene.people().size());
  std::vector<bool> seen(count + 1, false);
  for (int y = 0; y < rendered.person_label.rows; ++y) {
    const auto* row = rendered.person_label.ptr<std::uint16_t>(y);
    for (int x = 0; x < rendered.person_label.cols; ++x) {
      if (row[x] > 0 && row[x] <= count) seen[row[x]] = true;
    }
  }
  std::vector<PersonBox> boxes;
  const geometry::SE3 cam_from_world = world_from_cam.inverse();
  for (const Box& person : scene.people_boxes(frame)) {
    if (!seen[person.person_id]) continue;
    const auto bounds = projected_bounds(person, cam_from_world, scene.intrinsics());
    if (bounds) boxes.push_back({person.person_id, *bounds});
  }
  return boxes;
}

std::string settings_yaml(const SynthOptions& o) {
  const Intrinsics k = intrinsics_for(o.width, o.height);
  std::ostringstream out;
  out << "%YAML:1.0\n\n# crowdslam synth: " << (o.stereo ? "rectified stereo" : "RGB-D") << ", seed " << o.seed
      << "\nCamera.fx: " << format("%.6f", k.fx) << "\nCamera.fy: " << format("%.6f", k.fy)
      << "\nCamera.cx: " << format("%.6f", k.cx) << "\nCamera.cy: " << format("%.6f", k.cy)
      << "\n\nCamera.k1: 0.0\nCamera.k2: 0.0\nCamera.p1: 0.0\nCamera.p2: 0.0\nCamera.k3: 0.0\n"
      << "\nCamera.width: " << o.width << "\nCamera.height: " << o.height << "\nCamera.fps: 30.0\n"
      << "\n# stereo baseline times fx (RGB-D: a virtual baseline for the close/far point threshold)\n"
      << "Camera.bf: " << format("%.6f", o.stereo ? k.fx * kStereoBaselineM : 40.0)
      << "\n\n# colour order of the images (0: BGR, 1: RGB; the PNG files are read as usual)\nCamera.RGB: 1\n"
      << "\nThDepth: 40.0\n";
  if (!o.stereo) out << "DepthMapFactor: " << format("%.1f", kDepthFactor) << "\n";
  out << "\nORBextractor.nFeatures: 1000\nORBextractor.scaleFactor: 1.2\nORBextractor.nLevels: 8\n"
      << "ORBextractor.iniThFAST: 20\nORBextractor.minThFAST: 7\n";
  return out.str();
}

SequenceSummary write_sequence(const SynthOptions& options, const fs::path& out_dir_arg, const FrameProgress& on_frame) {
  const auto start = std::chrono::steady_clock::now();
  options.check();
  fs::path out_dir = out_dir_arg;
  if (!out_dir.has_filename()) out_dir = out_dir.parent_path();  // "dir/" -> "dir"
  if (out_dir.empty()) throw InputError("--out: empty output directory");
  if (out_dir.filename() == "." || out_dir.filename() == "..") {
    throw input_error(out_dir.string(), "name the output directory itself (not '.' or '..')");
  }
  prepare_output(options, out_dir);
  fs::path tmp = out_dir;
  tmp += ".tmp-" + std::to_string(::getpid());
  remove_quietly(tmp);
  remove_stale_temporary_dirs(out_dir);  // of a run killed with SIGKILL
  try {
    std::error_code ec;
    fs::create_directories(tmp, ec);
    if (ec) throw input_error(tmp.string(), "cannot create directory: " + ec.message());
    const Scene scene = Scene::build(options);
    if (!scene.photo_textures()) {
      spdlog::warn("synth: no photographs in '{}' (install opencv-doc); using procedural textures",
                   options.texture_dir);
    }
    const std::vector<FrameResult> results = SequenceWriter(scene, tmp, on_frame).write_frames();
    SequenceSummary summary = summarise(scene, results);
    write_text_files(scene, tmp, results, summary);
    if (fs::exists(out_dir, ec)) fs::remove_all(out_dir);
    fs::rename(tmp, out_dir, ec);
    if (ec) throw input_error(out_dir.string(), "cannot move the finished dataset into place: " + ec.message());
    summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return summary;
  } catch (...) {
    remove_quietly(tmp);
    throw;
  }
}

}  // namespace crowdslam::synth
