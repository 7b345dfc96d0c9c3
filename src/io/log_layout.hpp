// The columns of a run file's /samples table and the views over them, for a model and the chosen
// groups (h5log.hpp describes the file).  One table of names and units, and the one function that
// lays a Sample out in that order, side by side so they cannot drift apart.  Internal.
#pragma once

#include "soadyn/io/h5log.hpp"

#include <string>
#include <vector>

namespace soadyn::log {

struct Column {
  std::string name, unit;
};

// A view of /samples' columns [first, first + cols·bodies): rank 1 (cols = 0: one column),
// rank 2 (T × cols) or rank 3 (T × bodies × cols, bodies > 0).
struct View {
  std::string path;  // "/q", "/energy/kinetic", "/bodies/position"
  int first = 0, cols = 0, bodies = 0;
  std::vector<std::string> units;  // one per column of the view's last dimension (/sensitivities: per element)
};

struct Layout {
  std::vector<Column> columns;
  std::vector<View> views;
  std::vector<std::string> groups;  // "/energy", "/momentum", "/bodies" as needed
};

Layout layout(const Model& model, const LogGroups& groups);

// appends one row: the sample's numbers in the order of layout(model, groups).columns; the
// frames' poses (groups.frames) are computed from s.q with `data` (kinematics frames only)
void append_row(const Model& model, Data& data, const LogGroups& groups, const Sample& s, std::vector<double>& row);

// Every view a run file can hold, by path: layout() makes only these, and the reader (run_file.cpp)
// looks for these.  A view's columns of /samples are named by its path: "/energy/kinetic" is the one
// column "energy.kinetic", "/q" the columns "q.<coordinate>" (column_stem: the path's dots).
inline constexpr const char* kViewPaths[] = {
    "/time", "/q", "/qd", "/qdd", "/energy/kinetic", "/energy/potential", "/energy/total", "/energy/work_inputs",
    "/energy/dissipated", "/energy/impact_loss", "/momentum/linear", "/momentum/angular", "/bodies/position",
    "/bodies/orientation", "/bodies/com", "/control", "/frames/position", "/frames/orientation",
    "/sensitivities/initial_state", "/sensitivities/parameters", "/energy/work_prescribed", "/prescribed",
    "/loops/force", "/loops/closure"};

// "/energy/kinetic" → "energy.kinetic"
inline std::string column_stem(const std::string& view_path) {
  std::string s = view_path.substr(1);
  for (char& c : s)
    if (c == '/') c = '.';
  return s;
}
// the column is the view's: its stem itself (a one-column view) or the stem followed by "."
inline bool column_of(const std::string& column, const std::string& stem) {
  return column.compare(0, stem.size(), stem) == 0 && (column.size() == stem.size() || column[stem.size()] == '.');
}

// The shape layout() gives a view of rank 3 (T × items × per) with n columns, so a reader need not
// open the view: /bodies and /frames position and com 3 a row per item, orientation 4; /sensitivities
// nx items (x's dimension).  False for a view of rank 1 or 2, or n that does not divide.
inline bool rank3_shape(const std::string& view, long n, long nx, long& items, long& per) {
  const std::string v = view;
  if (v.rfind("/sensitivities/", 0) == 0) {
    items = nx, per = nx > 0 ? n / nx : 0;
  } else if (v.rfind("/bodies/", 0) == 0 || v.rfind("/frames/", 0) == 0) {
    per = v.size() >= 12 && v.compare(v.size() - 12, 12, "/orientation") == 0 ? 4 : 3;
    items = n / per;
  } else {
    return false;
  }
  return items > 0 && per > 0 && items * per == n;
}

// SI units of q and v, one per column (joint_traits)
std::vector<std::string> q_units(const Model& model);
std::vector<std::string> v_units(const Model& model);

}  // namespace soadyn::log
