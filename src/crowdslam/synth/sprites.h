#pragma once
// Person sprites: cut-outs of real people from MOT sequences, made at setup time and never committed
// (`crowdslam synth-sprites`, scripts/build_people_sprites.sh). The people of `crowdslam synth` are
// billboards textured with them (billboard.h).
//
// Extraction: for each ground-truth box of a MOT sequence (img1/NNNNNN.jpg, gt/gt.txt rows
// `frame,id,left,top,width,height,flag,...`, flag 0 = ignore) that is tall enough, fully inside the image
// and hardly covered by any other box, cv::grabCut (rectangle mode, initialised with the box) gives a
// foreground mask. Its largest connected part is kept when it is plausible: most of the foreground, a
// fill of the box within [min_fill, max_fill], reaching into the top and bottom 12 % of the box and 40 % of
// its width. The sprite is that part's bounding rectangle: head on the top row, feet on the bottom row. Up to
// `per_id` sprites per person (frames spread over the track, at least 10 frames apart), taken round-robin
// over all people so that the `max_sprites` cap keeps every identity. Deterministic: same files and decoder,
// same bytes.
//
// A sprite directory holds the PNGs (BGRA, alpha 0 or 255, colour 0 where transparent), named
// `<sequence>_<frame:06>_<id:03>.png`, and sprites.json:
//   {"generator": "crowdslam synth-sprites 1", "count": N, "options": {...},
//    "sequences": [{"name", "boxes", "candidates", "sprites", "rejected"}...],
//    "sprites": [{"file", "sequence", "frame", "id", "width", "height", "fill", "facing"}...]}
// where facing is +1 when the person walks to the right in its source images, -1 to the left, 0 unknown.
#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "crowdslam/synth/textures.h"

namespace crowdslam::synth {

constexpr const char* kSpriteGeneratorVersion = "crowdslam synth-sprites 1";

struct SpriteExtractOptions {
  int min_height_px = 120;   // ground-truth boxes at least this tall
  double max_overlap = 0.1;  // largest fraction of the box any other box of the frame may cover
  int border_px = 2;         // the box must be at least this far inside the image
  int iterations = 4;        // grabCut iterations
  int per_id = 3;            // sprites per person (distinct frames)
  int max_sprites = 150;
  double min_fill = 0.3;  // foreground area / box area
  double max_fill = 0.85;

  void check() const;  // throws InputError naming the option
};

struct SpriteRecord {
  std::string file;      // file name in the sprite directory
  std::string sequence;  // MOT sequence folder name
  int frame = 0;         // 1-based MOT frame
  int id = 0;            // MOT person id
  int width = 0;         // the PNG's size
  int height = 0;
  double fill = 0.0;  // opaque pixels / ground-truth box area
  int facing = 0;     // +1 walks right in its source, -1 left, 0 unknown
};

struct SequenceSprites {
  std::string name;
  int boxes = 0;       // ground-truth rows
  int candidates = 0;  // rows tall enough, inside the image and not overlapped
  int sprites = 0;
  int rejected = 0;  // grabCut masks that failed the plausibility tests
};

struct SpriteSet {
  std::vector<SpriteRecord> sprites;
  std::vector<SequenceSprites> sequences;
};

// The person's cut-out from `image` (CV_8UC3) inside `box` (pixels, inside the image): BGRA, alpha 0/255,
// cropped to the kept foreground's bounding rectangle; nullopt when the mask is implausible. `fill`
// receives the kept foreground area / box area. Deterministic (grabCut's random generator is seeded).
std::optional<cv::Mat> cut_out_person(const cv::Mat& image, const cv::Rect& box,
                                      const SpriteExtractOptions& options, double* fill = nullptr);

// MOT sequence folders: `path` itself when it holds img1/ and gt/gt.txt, else its subfolders that do,
// sorted by name. Empty when there are none.
std::vector<std::filesystem::path> find_mot_sequences(const std::filesystem::path& path);

// Called once per sequence, in order, with its figures when the extraction is done (for log lines).
using SequenceDone = std::function<void(const SequenceSprites&)>;

// Cuts sprites out of the sequences into out_dir and writes sprites.json. The directory appears
// atomically ("<out_dir>.tmp-<pid>" renamed at the end); an existing non-empty out_dir is an error unless
// `force`. Throws InputError naming the file (and line) for unreadable or malformed input.
SpriteSet extract_sprites(const std::vector<std::filesystem::path>& sequences,
                          const std::filesystem::path& out_dir, const SpriteExtractOptions& options,
                          bool force, const SequenceDone& on_sequence = {});

// <repo>/people_sprites (where scripts/build_people_sprites.sh puts them).
std::filesystem::path default_sprite_dir();
// $CROWDSLAM_SHARED/data/mot, else <repo>/../shared/data/mot (the build's shared directory).
std::filesystem::path default_mot_dir();
// True when `dir` holds a sprites.json.
bool has_sprites(const std::filesystem::path& dir);

// What `crowdslam synth --sprites OPTION` uses: option "" = the default directory when it holds sprites;
// "none" = boxes; anything else = that directory, which must hold sprites.json (else InputError naming
// it). `dir` is empty for box people; `notice` is then the one line to print (why, and how to build them).
struct SpriteChoice {
  std::string dir;
  std::string notice;
};
SpriteChoice resolve_sprite_dir(const std::string& option);

// A sprite ready for rendering.
struct Sprite {
  cv::Mat alpha;  // CV_8U, 0 or 255
  Texture
      colour;  // BGR; transparent texels filled from their opaque neighbours (no dark fringe when filtered)
  SpriteRecord record;
  double aspect() const { return static_cast<double>(alpha.cols) / alpha.rows; }
  // Bilinear alpha at level-0 texel coordinates (texel centres at integers) >= 0.5: the opaque test.
  bool opaque(double s, double t) const;
};

// Loads the sprites listed in dir/sprites.json, in that order. Throws InputError naming the file when the
// list or a sprite is missing or broken, or when it lists none.
std::vector<Sprite> load_sprites(const std::filesystem::path& dir);

}  // namespace crowdslam::synth
