#include "mtled/io/label_image.hpp"

#include <fmt/format.h>
#include <zlib.h>

#include <fstream>
#include <sstream>

#include "mtled/errors.hpp"

namespace fs = std::filesystem;

namespace mtled {

std::map<std::int32_t, std::int64_t> LabelImage::voxel_counts() const {
  std::map<std::int32_t, std::int64_t> counts;
  for (const std::int32_t label : labels) ++counts[label];
  return counts;
}

std::string gunzip(const std::string& bytes, const std::string& source) {
  z_stream stream{};
  if (inflateInit2(&stream, 16 + MAX_WBITS) != Z_OK) throw std::runtime_error("zlib could not start inflating");
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
  stream.avail_in = static_cast<uInt>(bytes.size());
  std::string out;
  char buffer[1 << 16];
  int status = Z_OK;
  while (status == Z_OK) {
    stream.next_out = reinterpret_cast<Bytef*>(buffer);
    stream.avail_out = sizeof buffer;
    status = inflate(&stream, Z_NO_FLUSH);
    out.append(buffer, sizeof buffer - stream.avail_out);
    if (status == Z_BUF_ERROR && stream.avail_in == 0) break;  // the stream ended early
  }
  inflateEnd(&stream);
  if (status != Z_STREAM_END)
    throw InputError(source, fmt::format("the gzip data is {} ({}); the file was cut short or is not gzip: save it "
                                         "again", status == Z_BUF_ERROR ? "truncated" : "corrupt",
                                         stream.msg != nullptr ? stream.msg : "zlib error"));
  return out;
}

LabelImage read_label_image(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in)
    throw InputError(file.string(), "cannot open the label map: check the path (relative paths are taken from the "
                                    "scene's folder)");
  std::ostringstream text;
  text << in.rdbuf();
  const std::string name = file.filename().string();
  const auto ends_with = [&](const std::string& suffix) {
    return name.size() >= suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  if (ends_with(".nrrd")) return parse_nrrd(text.str(), file.string());
  if (ends_with(".nii")) return parse_nifti(text.str(), file.string());
  if (ends_with(".nii.gz")) return parse_nifti(gunzip(text.str(), file.string()), file.string());
  throw InputError(file.string(), "unknown label-map format: name the file .nrrd, .seg.nrrd, .nii or .nii.gz (NRRD "
                                  "as 3D Slicer saves segmentations, NIfTI as ITK-SNAP and FreeSurfer do)");
}

}  // namespace mtled
