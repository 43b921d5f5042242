// Importer for the DBoW2 / ORB-SLAM2 text vocabulary (e.g. ORBvoc.txt):
//   line 1: "k L scoring weighting"
//   then one line per node after the root, node id = 1, 2, ...: "parent_id is_leaf d0 .. d31 weight"
//   with the 32 descriptor bytes as decimal numbers.
// Parsed from one buffer with std::from_chars (no per-line allocation): ORBvoc.txt has ~1M lines.
#include <cctype>
#include <charconv>
#include <cstring>
#include <fstream>
#include <sstream>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::bow {
namespace {

constexpr int kFieldsPerNode = 2 + feature::kDescriptorBytes + 1;

// Splits [begin, end) into whitespace-separated tokens (views into the buffer).
int tokenize(const char* begin, const char* end, std::string_view* tokens, int max_tokens) {
  int count = 0;
  const char* p = begin;
  while (p < end) {
    while (p < end && std::isspace(static_cast<unsigned char>(*p))) ++p;
    if (p >= end) break;
    const char* start = p;
    while (p < end && !std::isspace(static_cast<unsigned char>(*p))) ++p;
    if (count < max_tokens) tokens[count] = std::string_view(start, static_cast<std::size_t>(p - start));
    ++count;
  }
  return count;
}

template <typename T>
bool parse_number(std::string_view token, T& value) {
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && ptr == token.data() + token.size();
}

}  // namespace

Vocabulary Vocabulary::import_dbow2_text(const std::string& path) {
  check_regular_file(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw input_error(path, "cannot open vocabulary file");
  std::ostringstream content_stream;
  content_stream << in.rdbuf();
  const std::string content = content_stream.str();

  Vocabulary voc;
  voc.parent_.push_back(kNoNode);
  voc.descriptors_.assign(feature::kDescriptorBytes, 0);
  voc.weight_.push_back(0.0f);
  voc.word_id_.push_back(kNoWord);
  std::vector<std::uint8_t> declared_leaf{0};
  std::vector<int> node_line{0};

  std::string_view tokens[kFieldsPerNode];
  const char* p = content.data();
  const char* end = p + content.size();
  int line = 0;
  bool have_header = false;
  while (p < end) {
    const char* eol = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(end - p)));
    if (eol == nullptr) eol = end;
    ++line;
    const int count = tokenize(p, eol, tokens, kFieldsPerNode);
    p = eol + 1;
    if (count == 0) continue;
    if (!have_header) {
      int scoring = -1;
      int weighting = -1;
      if (count != 4 || !parse_number(tokens[0], voc.k_) || !parse_number(tokens[1], voc.levels_) ||
          !parse_number(tokens[2], scoring) || !parse_number(tokens[3], weighting)) {
        throw input_error(path, line, "expected the DBoW2 header \"k L scoring weighting\"");
      }
      if (scoring != 0 || weighting != 0) {
        throw input_error(path, line,
                          "only L1-norm scoring with TF-IDF weighting (\"0 0\") is supported, got " +
                              std::to_string(scoring) + " " + std::to_string(weighting));
      }
      have_header = true;
      continue;
    }
    if (count != kFieldsPerNode) {
      throw input_error(path, line,
                        "expected " + std::to_string(kFieldsPerNode) +
                            " fields (parent is_leaf 32 descriptor bytes weight), got " +
                            std::to_string(count));
    }
    long long parent = -1;
    int leaf = -1;
    double weight = 0.0;
    if (!parse_number(tokens[0], parent) || parent < 0 ||
        parent >= static_cast<long long>(voc.parent_.size())) {
      throw input_error(path, line, "bad parent id '" + std::string(tokens[0]) + "'");
    }
    if (!parse_number(tokens[1], leaf) || (leaf != 0 && leaf != 1)) {
      throw input_error(path, line, "bad is_leaf flag '" + std::string(tokens[1]) + "'");
    }
    for (int b = 0; b < feature::kDescriptorBytes; ++b) {
      int byte = -1;
      if (!parse_number(tokens[2 + b], byte) || byte < 0 || byte > 255) {
        throw input_error(path, line, "bad descriptor byte '" + std::string(tokens[2 + b]) + "'");
      }
      voc.descriptors_.push_back(static_cast<std::uint8_t>(byte));
    }
    if (!parse_number(tokens[kFieldsPerNode - 1], weight) || !(weight >= 0.0)) {
      throw input_error(path, line, "bad weight '" + std::string(tokens[kFieldsPerNode - 1]) + "'");
    }
    voc.parent_.push_back(static_cast<NodeId>(parent));
    voc.weight_.push_back(static_cast<float>(weight));
    voc.word_id_.push_back(kNoWord);
    declared_leaf.push_back(static_cast<std::uint8_t>(leaf));
    node_line.push_back(line);
  }
  if (!have_header) throw input_error(path, "empty vocabulary file");
  if (voc.parent_.size() < 2) throw input_error(path, "vocabulary has no nodes below the root");
  voc.finish(path, true);
  for (std::size_t i = 1; i < voc.parent_.size(); ++i) {
    const bool leaf = voc.word_id_[i] != kNoWord;
    if (leaf != (declared_leaf[i] == 1)) {
      throw input_error(path, node_line[i],
                        "node " + std::to_string(i) + " is declared " +
                            (declared_leaf[i] ? "a leaf but has children" : "inner but has no children"));
    }
  }
  return voc;
}

}  // namespace crowdslam::bow
