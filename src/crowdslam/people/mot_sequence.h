#pragma once
// MOTChallenge sequence folders: DIR/seqinfo.ini + DIR/img1/000001.jpg ... (io::open_dataset does not
// know this layout: its images are one level down).
//
// seqinfo.ini ([Sequence] section, key=value): imDir (default img1), frameRate (default 30), seqLength,
// imExt (default .jpg). With seqLength, frames are imDir/%06d<imExt> for 1..seqLength and each must exist;
// without it (or without seqinfo.ini), every image file in imDir sorted by name. Frame i (0-based) has
// timestamp i / frameRate. Errors throw InputError naming the file (and line).
#include <memory>
#include <string>

#include "crowdslam/io/dataset.h"

namespace crowdslam::people {

// DIR/seqinfo.ini exists, or DIR/img1/ is a folder.
bool looks_like_mot_sequence(const std::string& directory);

std::unique_ptr<io::Dataset> open_mot_sequence(const std::string& directory);

// What `crowdslam detect` reads: a MOT sequence folder, else anything io::open_source opens
// (TUM/Bonn, EuRoC, KITTI, image folder, video file, camera index).
std::unique_ptr<io::FrameSource> open_detection_source(const std::string& spec);

}  // namespace crowdslam::people
