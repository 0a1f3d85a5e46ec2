#pragma once
// 3D Slicer markups files (.mrk.json): the placed control points of a file's first markup (a point list, a line),
// with their labels, in metres and in the file's coordinateSystem. The needle reads a trajectory from one (its first
// two points), a fit reads markers from two (before and after, matched by label).
#include <filesystem>
#include <string>
#include <vector>

#include "mtled/types.hpp"

namespace mtled {

struct MarkupsPoint {
  std::string label;
  Vec3 position = Vec3::Zero();  // m
};

struct MarkupsPoints {
  std::string type;                  // the markup's "type" (Fiducial, Line, ...), for messages
  std::string frame;                 // "LPS" or "RAS"
  std::vector<MarkupsPoint> points;  // the defined control points, in the file's order
};

// InputError naming the file (and the JSON pointer within it) when it is not a markups file mtled can read.
MarkupsPoints read_markups(const std::filesystem::path& file);
MarkupsPoints parse_markups(const std::string& text, const std::string& label);  // the file's text

// The same point in the other of Slicer's two frames (LPS and RAS differ in the sign of x and y).
inline Vec3 flip_lps_ras(const Vec3& x) { return Vec3(-x[0], -x[1], x[2]); }
// Whether points in frame `from` need flip_lps_ras to lie in a mesh recording frame `to`: both known and different
// (an empty frame: the scene's own coordinates, or a mesh that records none).
inline bool frames_differ(const std::string& from, const std::string& to) {
  return !from.empty() && !to.empty() && from != to;
}

}  // namespace mtled
