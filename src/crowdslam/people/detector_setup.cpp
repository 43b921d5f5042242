#include "crowdslam/people/detector_setup.h"

namespace crowdslam::people {

DetectorSetup detector_setup(const io::DetectorSettings& d, const std::string& spec_override) {
  DetectorSetup s;
  std::string spec = spec_override.empty() ? d.model_cfg : spec_override;
  if (spec.empty()) spec = "body";
  s.model = resolve_model(spec);
  if (!d.model_weights.empty() && spec_override.empty()) s.model.weights = d.model_weights;
  if (s.model.name.empty()) s.model.person_class = d.person_class;
  if (d.backend != "auto") s.model.backend = parse_backend(d.backend);
  if (d.preprocess != "auto") {
    preprocessing_preset(d.preprocess);  // validates the name, naming the key
    s.model.preprocess = d.preprocess;
  }
  s.options.input_size = d.input_size;
  s.options.input_width = d.input_width;
  s.options.input_height = d.input_height;
  if (d.resize != "auto") s.options.resize = parse_resize_mode(d.resize);
  s.options.confidence = d.confidence;
  s.options.nms = d.nms;
  s.options.person_class = s.model.person_class;
  return s;
}

}  // namespace crowdslam::people
