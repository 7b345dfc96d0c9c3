// soadyn export RUN.h5 --csv out.csv [--json out.json] [--columns a,b] [--every K]: a run's
// /samples as text, each column headed by its name and unit.
//
// Reads only /samples and its attributes column_names and column_units (W strings each), through
// the library's RunReader (run_file.hpp), in single-writer/multiple-reader mode so a run that is
// still going (or was killed) exports the rows it has flushed so far.  Rows are read in blocks, so
// a file of any length exports in bounded memory.  Outputs are written under a temporary name and renamed into place.
#include "cli.hpp"

#include "soadyn/io/h5log.hpp"
#include "soadyn/io/run_file.hpp"
#include "soadyn/multibody/text.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

namespace soadyn::cli {

namespace {

namespace fs = std::filesystem;

// the run's /samples (RunReader): its rows when opened, W columns, their names and units
struct Samples {
  RunReader run;
  std::uint64_t rows = 0, width = 0;
  std::vector<std::string> names, units;
};

Samples open_samples(const std::string& path) {
  Samples s{RunReader(path), 0, 0, {}, {}};  // a regular file, or the reason it is not (input_file.hpp)
  if (s.run.column_names().empty()) throw Error(path + ": no /samples (not a run file from soadyn run?)");
  s.rows = s.run.rows(), s.width = s.run.column_names().size();
  s.names = s.run.column_names(), s.units = s.run.column_units();
  return s;
}

// the joint or body a column belongs to: q.<joint>[.<part>], qd.…, qdd.…, bodies.<what>.<body>.<axis>
bool belongs_to(const std::string& column, const std::string& name) {
  for (const char* g : {"q.", "qd.", "qdd."}) {
    const size_t n = std::strlen(g);
    if (column.compare(0, n, g) == 0) {
      const std::string rest = column.substr(n);
      return rest == name || rest.compare(0, name.size() + 1, name + ".") == 0;
    }
  }
  if (column.compare(0, 7, "bodies.") == 0) {
    const size_t a = column.find('.', 7), b = column.rfind('.');
    return a != std::string::npos && b > a && column.compare(a + 1, b - a - 1, name) == 0;
  }
  return false;
}

// --columns: each item a column name, a group prefix (q, bodies.position) or a joint or body name
std::vector<size_t> select_columns(const Samples& s, const std::string& list, const std::string& path) {
  std::vector<size_t> cols;
  auto add = [&](size_t c) {
    if (std::find(cols.begin(), cols.end(), c) == cols.end()) cols.push_back(c);
  };
  for (size_t c = 0; c < s.width; ++c)
    if (s.names[c] == "time") add(c);  // time always first
  if (list.empty()) {
    for (size_t c = 0; c < s.width; ++c) add(c);
    return cols;
  }
  size_t from = 0;
  while (from <= list.size()) {
    const size_t comma = std::min(list.find(',', from), list.size());
    const std::string item = list.substr(from, comma - from);
    from = comma + 1;
    if (item.empty()) throw Error("--columns: an empty name in '" + list + "'");
    std::vector<size_t> found;
    for (size_t c = 0; c < s.width; ++c)
      if (s.names[c] == item) found.push_back(c);
    if (found.empty())
      for (size_t c = 0; c < s.width; ++c)
        if (s.names[c].compare(0, item.size() + 1, item + ".") == 0) found.push_back(c);
    if (found.empty())
      for (size_t c = 0; c < s.width; ++c)
        if (belongs_to(s.names[c], item)) found.push_back(c);
    if (found.empty())
      throw Error(path + ": --columns: no column, group, joint or body named '" + item +
                  "' (soadyn export " + path + " --list shows the columns)");
    for (size_t c : found) add(c);
  }
  return cols;
}

// the shortest text that reads back as the same double (as Python's repr): "nan", "inf", "-inf";
// "-0.0", not "-0", which JSON readers take for the integer 0
void number(std::string& out, double x) {
  if (x == 0 && std::signbit(x)) {
    out += "-0.0";
    return;
  }
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  out.append(buf, r.ptr);
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const unsigned char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\', out += char(c);
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += char(c);
    }
  }
  return out + "\"";
}

}  // namespace

void add_export(CLI::App& app, ExportOptions& o) {
  CLI::App* c = app.add_subcommand(
      "export",
      "Write a run's samples as CSV (or JSON), each column headed by its name and unit, every number\n"
      "to full precision.  Works on a run that is still going: the rows flushed so far.\n"
      "Exit status: 0 written, 2 bad input (no such file or column), 4 writing failed.");
  c->add_option("RUN", o.run, "HDF5 run file from soadyn run")->required();
  c->add_option("--csv", o.csv, "CSV file to write ('-': stdout); header 'time [s],q.left [rad],...'");
  c->add_option("--json", o.json,
                "JSON file to write ('-': stdout): {\"file\", \"columns\", \"units\", \"rows\": [[...], ...]}, "
                "non-finite numbers as null");
  c->add_option("--columns", o.columns,
                "comma-separated: column names (q.left), groups (q, energy, bodies.position) or joint/body "
                "names (left: q.left, qd.left, qdd.left); time always comes first (default: every column)");
  c->add_option("--every", o.every, "keep every K-th row, the first included (default 1)")->check(CLI::Validator(
      [](std::string& v) {
        const bool whole = !v.empty() && v.find_first_not_of("0123456789") == std::string::npos;
        return whole && v.find_first_not_of('0') != std::string::npos ? std::string()
                                                                       : "expected a whole number K >= 1, got '" + v + "'";
      },
      "K >= 1"));
  c->add_flag("--list", o.list, "print the columns (name, unit) and the row count, write nothing");
  c->add_flag("--force", o.force,
              "replace outputs that are not soadyn exports (never an input, a file in use; a device or FIFO is "
              "written in place)");
  c->add_flag("-q,--quiet", o.quiet, "no summary on stderr");
}

namespace {

// the header of a CSV ("name [unit]" per column) or a JSON output (file, columns, units, the rows' opening)
std::string header(bool json, const Samples& s, const std::vector<size_t>& cols, const std::string& run) {
  std::string h;
  if (!json) {
    for (size_t k = 0; k < cols.size(); ++k)
      h += (k ? "," : "") + csv_field(s.names[cols[k]] + " [" + s.units[cols[k]] + "]");
    h += "\n";
  } else {
    h = "{\"file\": " + json_string(run) + ",\n \"columns\": [";
    for (size_t k = 0; k < cols.size(); ++k) h += (k ? ", " : "") + json_string(s.names[cols[k]]);
    h += "],\n \"units\": [";
    for (size_t k = 0; k < cols.size(); ++k) h += (k ? ", " : "") + json_string(s.units[cols[k]]);
    h += "],\n \"rows\": [";
  }
  return h;
}

// the rows written and the first and last of their first column
struct Written {
  std::uint64_t rows = 0;
  double t_first = 0, t_last = 0;
};

// rows, read in blocks of about 4 MB: rows 0, K, 2K, … (K = every) of the extent seen at opening
Written write_rows(Samples& s, const std::vector<size_t>& cols, long every,
                   const std::vector<std::unique_ptr<TextWriter>>& writers, const std::vector<bool>& is_json) {
  const std::uint64_t K = std::uint64_t(every), block = std::max<std::uint64_t>(1, (std::uint64_t(1) << 19) / std::max<std::uint64_t>(1, s.width));
  std::vector<double> buf;
  std::string csv_text, json_text;
  std::uint64_t written = 0;
  double t_first = 0, t_last = 0;
  for (std::uint64_t r0 = 0; r0 < s.rows; r0 += block) {
    const std::uint64_t n = std::min(block, s.rows - r0);
    buf.resize(size_t(n * s.width));
    s.run.read_rows(r0, n, buf.data());
    csv_text.clear(), json_text.clear();
    for (std::uint64_t r = (K - r0 % K) % K; r < n; r += K) {
      const double* row = buf.data() + r * s.width;
      for (size_t k = 0; k < cols.size(); ++k) {
        const double x = row[cols[k]];
        if (k) csv_text += ',';
        number(csv_text, x);
        json_text += k ? ", " : (written ? ",\n  [" : "\n  [");
        if (std::isfinite(x)) number(json_text, x);
        else json_text += "null";
      }
      csv_text += '\n', json_text += ']';
      if (written == 0) t_first = row[cols[0]];
      t_last = row[cols[0]];
      ++written;
    }
    for (size_t i = 0; i < writers.size(); ++i) writers[i]->write(is_json[i] ? json_text : csv_text);
  }
  return {written, t_first, t_last};
}

}  // namespace

int run_export(const ExportOptions& o) {
  if (!o.list && o.csv.empty() && o.json.empty()) throw Error("export: give --csv FILE or --json FILE (or --list)");
  if (o.csv == "-" && o.json == "-") throw Error("export: only one of --csv and --json can be stdout");
  Samples s = open_samples(o.run);
  if (o.list) {
    std::printf("%s: %llu rows, %llu columns\n", o.run.c_str(), static_cast<unsigned long long>(s.rows),
                static_cast<unsigned long long>(s.width));
    for (size_t c = 0; c < s.width; ++c)
      std::printf("%s [%s]\n", printable(s.names[c]).c_str(), printable(s.units[c]).c_str());
    return 0;
  }
  const std::vector<size_t> cols = select_columns(s, o.columns, o.run);
  // every output is checked before any is touched, and nothing is written if one is refused
  const std::vector<OutputTarget> targets =
      check_outputs({{o.csv, OutputKind::Csv}, {o.json, OutputKind::Json}}, {o.run}, o.force);

  std::vector<std::unique_ptr<TextWriter>> writers;
  std::vector<bool> is_json;
  try {
    if (!o.csv.empty()) writers.push_back(std::make_unique<TextWriter>(o.csv, targets[0])), is_json.push_back(false);
    if (!o.json.empty()) writers.push_back(std::make_unique<TextWriter>(o.json, targets[1])), is_json.push_back(true);
    for (size_t i = 0; i < writers.size(); ++i) writers[i]->write(header(is_json[i], s, cols, o.run));
    const Written w = write_rows(s, cols, o.every, writers, is_json);
    for (size_t i = 0; i < writers.size(); ++i) {
      if (is_json[i]) writers[i]->write("]}\n");
      writers[i]->commit();
    }
    char time_range[80] = "";
    if (w.rows && s.names[cols[0]] == "time")
      std::snprintf(time_range, sizeof time_range, " (t = %g to %g s)", w.t_first, w.t_last);
    if (!o.quiet)
      for (auto& out : writers)
        if (out->path() != "-")
          std::fprintf(stderr, "wrote %s: %llu rows x %zu columns%s\n", out->path().c_str(),
                       static_cast<unsigned long long>(w.rows), cols.size(), time_range);
  } catch (const IoError& e) {
    std::fprintf(stderr, "soadyn: error: %s\n", e.what());
    return 4;
  }
  return 0;
}

}  // namespace soadyn::cli
