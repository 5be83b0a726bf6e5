#include "tools/vocabulary.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <span>

#include "skyloc/platform/bytes.h"
#include "skyloc/platform/crc32.h"

namespace skyloc::tools {
namespace {

// Layout (little-endian, as every skyloc target; docs/FABMAP.md):
//   header, kHeaderBytes:
//     0 magic "SKYLOCFM"    8 version u32        12 header bytes u32
//    16 image width u32    20 image height u32  24 max features u32   28 descriptor u32
//    32 descriptor dim u32 36 words u32         40 root word u32      44 samples u32
//    48 sample word ids u64                     56 p(z|e) f64         64 p(z|not e) f64
//    72 payload bytes u64  80 payload CRC u32   84 header CRC u32 (of bytes 0..83)
//   payload: centres f32[words x dim], parent i32[words], p(z) f64[words],
//     p(z|parent) f64[words], p(z|no parent) f64[words], sample offsets u64[samples + 1],
//     sample word ids u32[sample word ids]
constexpr char kMagic[8] = {'S', 'K', 'Y', 'L', 'O', 'C', 'F', 'M'};
constexpr std::size_t kHeaderBytes = 88;
constexpr std::uint32_t kMaxWords = 1u << 20;
constexpr std::uint32_t kMaxDim = 4096;

template <typename T>
void Put(std::vector<std::uint8_t>* out, std::size_t at, T v) {
  StoreBytes(out->data() + at, v);
}
template <typename T>
void Append(std::vector<std::uint8_t>* out, T v) {
  const std::size_t at = out->size();
  out->resize(at + sizeof v);
  Put(out, at, v);
}

std::uint32_t CrcOf(const std::uint8_t* p, std::size_t n) {
  return Crc32(std::span<const std::uint8_t>(p, n));
}

std::uint64_t PayloadBytes(std::uint64_t words, std::uint64_t dim, std::uint64_t samples,
                           std::uint64_t ids) {
  return words * dim * 4 + words * 4 + words * 8 * 3 + (samples + 1) * 8 + ids * 4;
}

bool IsProbability(double p) {
  return p > 0 && p < 1;  // the model smooths every probability into [0.01, 0.99]
}

}  // namespace

Status CheckVocabulary(const Vocabulary& v) {
  const FeatureSettings& f = v.features;
  if (f.width < 16 || f.height < 16 || f.width > 8192 || f.height > 8192 || f.max_features < 1)
    return Status::Error(StatusCode::kInvalidArgument, "bad feature settings %dx%d, %d features",
                         f.width, f.height, f.max_features);
  if (f.descriptor != kDescriptorSift || f.descriptor_dim != kSiftDim) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "descriptor kind %u of %d values; this skyloc uses SIFT (kind 1, 128)",
                         f.descriptor, f.descriptor_dim);
  }
  const auto n = static_cast<std::size_t>(v.words);
  if (v.words < 2 || n > kMaxWords)
    return Status::Error(StatusCode::kInvalidArgument, "%d words (need 2..%u)", v.words, kMaxWords);
  if (v.centres.size() != n * static_cast<std::size_t>(f.descriptor_dim))
    return Status::Error(StatusCode::kInvalidArgument, "%zu centre values for %d words",
                         v.centres.size(), v.words);
  for (const float c : v.centres)
    if (!std::isfinite(c))
      return Status::Error(StatusCode::kInvalidArgument, "a word centre is not finite");
  const ChowLiuTree& t = v.tree;
  if (t.words != v.words || t.parent.size() != n || t.p_z.size() != n ||
      t.p_z_given_parent.size() != n || t.p_z_given_no_parent.size() != n || t.root < 0 ||
      static_cast<std::size_t>(t.root) >= n || t.parent[static_cast<std::size_t>(t.root)] != t.root)
    return Status::Error(StatusCode::kInvalidArgument, "the Chow-Liu tree does not fit %d words",
                         v.words);
  // Every word must reach the root, in at most `words` steps (no cycles).
  for (std::size_t q = 0; q < n; ++q) {
    if (!IsProbability(t.p_z[q]) || !IsProbability(t.p_z_given_parent[q]) ||
        !IsProbability(t.p_z_given_no_parent[q]))
      return Status::Error(StatusCode::kInvalidArgument,
                           "word %zu has a probability outside (0, 1)", q);
    std::size_t at = q, steps = 0;
    while (static_cast<int>(at) != t.root) {
      const std::int32_t p = t.parent[at];
      if (p < 0 || static_cast<std::size_t>(p) >= n || ++steps > n ||
          static_cast<std::size_t>(p) == at)
        return Status::Error(StatusCode::kInvalidArgument,
                             "word %zu's Chow-Liu parents do not lead to the root", q);
      at = static_cast<std::size_t>(p);
    }
  }
  if (!(v.p_z_given_not_e >= 0 && v.p_z_given_not_e < v.p_z_given_e && v.p_z_given_e <= 1))
    return Status::Error(StatusCode::kInvalidArgument, "detector model p(z|e) %g, p(z|not e) %g",
                         v.p_z_given_e, v.p_z_given_not_e);
  if (v.samples.empty())
    return Status::Error(StatusCode::kInvalidArgument, "no training images (new-place model)");
  for (std::size_t s = 0; s < v.samples.size(); ++s) {
    if (Status st = CheckWordList(v.samples[s], v.words); !st.ok())
      return st.AddContext("training image %zu", s);
  }
  return Status::Ok();
}

Status SaveVocabulary(const std::string& path, const Vocabulary& v) {
  if (Status s = CheckVocabulary(v); !s.ok())
    return s.AddContext("cannot write vocabulary %s", path.c_str());
  std::vector<std::uint8_t> b(kHeaderBytes, 0);
  std::uint64_t ids = 0;
  for (const WordList& s : v.samples)
    ids += s.size();
  // Payload first, then the header that describes it.
  for (const float c : v.centres)
    Append(&b, c);
  for (const std::int32_t p : v.tree.parent)
    Append(&b, p);
  for (const auto* table : {&v.tree.p_z, &v.tree.p_z_given_parent, &v.tree.p_z_given_no_parent})
    for (const double p : *table)
      Append(&b, p);
  std::uint64_t offset = 0;
  Append(&b, offset);
  for (const WordList& s : v.samples) {
    offset += s.size();
    Append(&b, offset);
  }
  for (const WordList& s : v.samples)
    for (const std::uint32_t q : s)
      Append(&b, q);
  const std::uint64_t payload = b.size() - kHeaderBytes;
  std::memcpy(b.data(), kMagic, sizeof kMagic);
  Put<std::uint32_t>(&b, 8, kVocabularyVersion);
  Put<std::uint32_t>(&b, 12, static_cast<std::uint32_t>(kHeaderBytes));
  Put<std::uint32_t>(&b, 16, static_cast<std::uint32_t>(v.features.width));
  Put<std::uint32_t>(&b, 20, static_cast<std::uint32_t>(v.features.height));
  Put<std::uint32_t>(&b, 24, static_cast<std::uint32_t>(v.features.max_features));
  Put<std::uint32_t>(&b, 28, v.features.descriptor);
  Put<std::uint32_t>(&b, 32, static_cast<std::uint32_t>(v.features.descriptor_dim));
  Put<std::uint32_t>(&b, 36, static_cast<std::uint32_t>(v.words));
  Put<std::uint32_t>(&b, 40, static_cast<std::uint32_t>(v.tree.root));
  Put<std::uint32_t>(&b, 44, static_cast<std::uint32_t>(v.samples.size()));
  Put<std::uint64_t>(&b, 48, ids);
  Put<double>(&b, 56, v.p_z_given_e);
  Put<double>(&b, 64, v.p_z_given_not_e);
  Put<std::uint64_t>(&b, 72, payload);
  Put<std::uint32_t>(&b, 80, CrcOf(b.data() + kHeaderBytes, payload));
  Put<std::uint32_t>(&b, 84, CrcOf(b.data(), 84));

  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "cannot create vocabulary %s", tmp.c_str());
  }
  std::size_t done = 0;
  while (done < b.size()) {
    const ssize_t w = ::write(fd, b.data() + done, b.size() - done);
    if (w < 0 && errno == EINTR)
      continue;
    if (w <= 0) {
      const int saved = w < 0 ? errno : EIO;
      ::close(fd);
      ::unlink(tmp.c_str());
      return Status::FromErrno(saved, "cannot write vocabulary %s", tmp.c_str());
    }
    done += static_cast<std::size_t>(w);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const int saved = errno;
    ::unlink(tmp.c_str());
    return Status::FromErrno(saved, "cannot write vocabulary %s", tmp.c_str());
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int saved = errno;
    ::unlink(tmp.c_str());
    return Status::FromErrno(saved, "cannot rename %s to %s", tmp.c_str(), path.c_str());
  }
  return Status::Ok();
}

Result<Vocabulary> LoadVocabulary(const std::string& path) {
  const char* p = path.c_str();
  std::FILE* f = std::fopen(p, "rb");
  if (f == nullptr) {
    const int saved = errno;
    return Status::FromErrno(saved,
                             "cannot open vocabulary %s (write one with skyloc fabmap-train)", p);
  }
  std::vector<std::uint8_t> b;
  std::uint8_t chunk[65536];
  std::size_t got = 0;
  while ((got = std::fread(chunk, 1, sizeof chunk, f)) > 0)
    b.insert(b.end(), chunk, chunk + got);
  const bool read_error = std::ferror(f) != 0;
  std::fclose(f);
  if (read_error)
    return Status::Error(StatusCode::kUnavailable, "cannot read vocabulary %s", p);
  const auto corrupt = [p](const char* what) {
    return Status::Error(StatusCode::kDataLoss,
                         "vocabulary %s is corrupt (%s): write it again with skyloc fabmap-train",
                         p, what);
  };
  if (b.size() < 12 || std::memcmp(b.data(), kMagic, sizeof kMagic) != 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "%s is not a skyloc FAB-MAP vocabulary (no SKYLOCFM magic): give the "
                         "file skyloc fabmap-train wrote",
                         p);
  }
  const std::uint32_t version = LoadBytes<std::uint32_t>(b.data() + 8);
  if (version != kVocabularyVersion) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "vocabulary %s has format version %u; this skyloc reads version %u: %s", p,
                         version, kVocabularyVersion,
                         version > kVocabularyVersion
                             ? "use the skyloc that wrote it, or train it again with this one"
                             : "train it again with skyloc fabmap-train");
  }
  if (b.size() < kHeaderBytes || LoadBytes<std::uint32_t>(b.data() + 12) != kHeaderBytes)
    return corrupt("truncated header");
  if (LoadBytes<std::uint32_t>(b.data() + 84) != CrcOf(b.data(), 84))
    return corrupt("header checksum mismatch");
  Vocabulary v;
  v.features.width = static_cast<int>(LoadBytes<std::uint32_t>(b.data() + 16));
  v.features.height = static_cast<int>(LoadBytes<std::uint32_t>(b.data() + 20));
  v.features.max_features = static_cast<int>(LoadBytes<std::uint32_t>(b.data() + 24));
  v.features.descriptor = LoadBytes<std::uint32_t>(b.data() + 28);
  const std::uint32_t dim = LoadBytes<std::uint32_t>(b.data() + 32);
  const std::uint32_t words = LoadBytes<std::uint32_t>(b.data() + 36);
  const std::uint32_t samples = LoadBytes<std::uint32_t>(b.data() + 44);
  const std::uint64_t ids = LoadBytes<std::uint64_t>(b.data() + 48);
  const std::uint64_t payload = LoadBytes<std::uint64_t>(b.data() + 72);
  if (dim > kMaxDim || words > kMaxWords || ids > (1ull << 40))
    return corrupt("impossible sizes");
  if (payload != PayloadBytes(words, dim, samples, ids) || b.size() - kHeaderBytes != payload)
    return corrupt("size does not match its header");
  if (LoadBytes<std::uint32_t>(b.data() + 80) != CrcOf(b.data() + kHeaderBytes, payload))
    return corrupt("payload checksum mismatch");
  v.features.descriptor_dim = static_cast<int>(dim);
  v.words = static_cast<int>(words);
  v.tree.words = v.words;
  v.tree.root = static_cast<int>(LoadBytes<std::uint32_t>(b.data() + 40));
  v.p_z_given_e = LoadBytes<double>(b.data() + 56);
  v.p_z_given_not_e = LoadBytes<double>(b.data() + 64);
  const std::uint8_t* at = b.data() + kHeaderBytes;
  v.centres.resize(static_cast<std::size_t>(words) * dim);
  for (float& c : v.centres) {
    c = LoadBytes<float>(at);
    at += 4;
  }
  v.tree.parent.resize(words);
  for (std::int32_t& q : v.tree.parent) {
    q = LoadBytes<std::int32_t>(at);
    at += 4;
  }
  for (auto* table : {&v.tree.p_z, &v.tree.p_z_given_parent, &v.tree.p_z_given_no_parent}) {
    table->resize(words);
    for (double& x : *table) {
      x = LoadBytes<double>(at);
      at += 8;
    }
  }
  std::vector<std::uint64_t> offsets(static_cast<std::size_t>(samples) + 1);
  for (std::uint64_t& o : offsets) {
    o = LoadBytes<std::uint64_t>(at);
    at += 8;
  }
  const std::uint8_t* ids_at = at;
  if (offsets.front() != 0 || offsets.back() != ids)
    return corrupt("training image offsets do not add up");
  for (std::size_t s = 0; s < samples; ++s)
    if (offsets[s + 1] < offsets[s])
      return corrupt("training image offsets go backwards");
  v.samples.resize(samples);
  for (std::size_t s = 0; s < samples; ++s) {
    for (std::uint64_t k = offsets[s]; k < offsets[s + 1]; ++k)
      v.samples[s].push_back(LoadBytes<std::uint32_t>(ids_at + 4 * k));
  }
  if (Status s = CheckVocabulary(v); !s.ok()) {
    return Status::Error(StatusCode::kDataLoss,
                         "vocabulary %s is inconsistent (%s): train it again with skyloc "
                         "fabmap-train",
                         p, s.message());
  }
  return v;
}

}  // namespace skyloc::tools
