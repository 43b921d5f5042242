// Binary vocabulary file: save, load (one read of the whole file, flat arrays) and format detection.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <memory>

#include "crowdslam/feature/descriptor.h"
#include "crowdslam/bow/vocabulary.h"
#include "crowdslam/util/atomic_file.h"
#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"

namespace crowdslam::bow {
namespace {

constexpr char kMagic[8] = {'C', 'S', 'L', 'M', 'V', 'O', 'C', '1'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kHeaderBytes = 32;
constexpr std::size_t kNodeBytes = 4 + feature::kDescriptorBytes + 4 + 4;

static_assert(sizeof(float) == 4, "IEEE single precision expected");
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the vocabulary file format is little-endian");

template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

template <typename T>
T get(const char* at) {
  T value;
  std::memcpy(&value, at, sizeof(T));
  return value;
}

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

// The whole file in one buffer.
std::vector<char> read_all(const std::string& path) {
  check_regular_file(path);  // a directory or /dev/zero is never read
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) throw input_error(path, "cannot open vocabulary file");
  if (std::fseek(file.get(), 0, SEEK_END) != 0) throw input_error(path, "cannot seek in vocabulary file");
  const long size = std::ftell(file.get());
  if (size < 0) throw input_error(path, "cannot get the size of the vocabulary file");
  std::rewind(file.get());
  std::vector<char> buffer(static_cast<std::size_t>(size));
  if (size > 0 && std::fread(buffer.data(), 1, buffer.size(), file.get()) != buffer.size()) {
    throw input_error(path, "cannot read vocabulary file");
  }
  return buffer;
}

bool has_magic(const std::string& path) {
  check_regular_file(path);
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) throw input_error(path, "cannot open vocabulary file");
  char magic[sizeof kMagic] = {};
  const std::size_t got = std::fread(magic, 1, sizeof magic, file.get());
  // A file cut inside the magic is still ours (load() reports it as truncated).
  return got > 0 && std::memcmp(magic, kMagic, got) == 0;
}

}  // namespace

void Vocabulary::save(const std::string& path) const {
  std::string out;
  out.reserve(kHeaderBytes + kNodeBytes * num_nodes());
  out.append(kMagic, sizeof kMagic);
  put<std::uint32_t>(out, kVersion);
  put<std::uint32_t>(out, feature::kDescriptorBytes);
  put<std::uint32_t>(out, static_cast<std::uint32_t>(k_));
  put<std::uint32_t>(out, static_cast<std::uint32_t>(levels_));
  put<std::uint64_t>(out, num_nodes());
  for (std::size_t i = 0; i < num_nodes(); ++i) {
    put<std::uint32_t>(out, parent_[i]);
    out.append(reinterpret_cast<const char*>(node_descriptor(static_cast<NodeId>(i))),
               feature::kDescriptorBytes);
    put<float>(out, weight_[i]);
    put<std::uint32_t>(out, word_id_[i]);
  }
  AtomicFile file(path);
  file.stream().write(out.data(), static_cast<std::streamsize>(out.size()));
  file.commit();
}

Vocabulary Vocabulary::load(const std::string& path) {
  const std::vector<char> data = read_all(path);
  const std::size_t magic_bytes = std::min(data.size(), sizeof kMagic);
  if (data.size() < kHeaderBytes && std::memcmp(data.data(), kMagic, magic_bytes) == 0) {
    throw input_error(path, "truncated vocabulary file (incomplete header)");
  }
  if (std::memcmp(data.data(), kMagic, magic_bytes) != 0) {
    throw input_error(path, "not a crowdslam vocabulary file (wrong magic)");
  }
  const auto version = get<std::uint32_t>(data.data() + 8);
  if (version != kVersion) {
    throw input_error(path, "unsupported vocabulary file version " + std::to_string(version));
  }
  const auto descriptor_bytes = get<std::uint32_t>(data.data() + 12);
  if (descriptor_bytes != feature::kDescriptorBytes) {
    throw input_error(path, "vocabulary has descriptors of " + std::to_string(descriptor_bytes) +
                                " bytes, ORB needs " + std::to_string(feature::kDescriptorBytes));
  }
  Vocabulary voc;
  voc.k_ = static_cast<int>(get<std::uint32_t>(data.data() + 16));
  voc.levels_ = static_cast<int>(get<std::uint32_t>(data.data() + 20));
  const auto count = get<std::uint64_t>(data.data() + 24);
  const std::size_t body = data.size() - kHeaderBytes;
  if (count > body / kNodeBytes || body != count * kNodeBytes) {
    if (count > body / kNodeBytes) {
      throw input_error(path, "truncated vocabulary file: header announces " + std::to_string(count) +
                                  " nodes, file holds " + std::to_string(body / kNodeBytes));
    }
    throw input_error(path, "vocabulary file has " + std::to_string(body - count * kNodeBytes) +
                                " unexpected trailing bytes");
  }
  const std::size_t n = static_cast<std::size_t>(count);
  voc.parent_.resize(n);
  voc.descriptors_.resize(n * feature::kDescriptorBytes);
  voc.weight_.resize(n);
  voc.word_id_.resize(n);
  const char* at = data.data() + kHeaderBytes;
  for (std::size_t i = 0; i < n; ++i, at += kNodeBytes) {
    voc.parent_[i] = get<std::uint32_t>(at);
    std::memcpy(&voc.descriptors_[i * feature::kDescriptorBytes], at + 4, feature::kDescriptorBytes);
    voc.weight_[i] = get<float>(at + 4 + feature::kDescriptorBytes);
    voc.word_id_[i] = get<std::uint32_t>(at + 8 + feature::kDescriptorBytes);
  }
  voc.finish(path, false);
  return voc;
}

Vocabulary Vocabulary::read(const std::string& path) {
  return has_magic(path) ? load(path) : import_dbow2_text(path);
}

}  // namespace crowdslam::bow
