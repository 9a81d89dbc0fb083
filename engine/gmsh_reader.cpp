// Reads a Gmsh mesh (MSH 2.2 or 4.1, ASCII) into a TriangleMesh (engine/triangle_mesh.hpp).
//
// Every rejection is a one-line SceneError that starts with the file's path and names the line and, for a bad
// element or node, its Gmsh number, so that the user can find it in the file or in Gmsh's GUI. The TriangleMesh
// constructor names triangles by their 0-based index among the triangles, which a user cannot see in the file, so
// everything it would refuse about an element (inverted, degenerate, non-manifold) is checked here first, by
// Gmsh number; the constructor's own checks remain as a backstop.
#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "engine/scene.hpp"
#include "engine/triangle_mesh.hpp"

namespace mpm {
namespace {

// Every node or element takes at least this many bytes of the file ("1 0 0 0\n" is 8): a count larger than the
// file could hold is refused before anything is allocated for it.
constexpr std::uintmax_t kMinBytesPerItem = 4;

constexpr int kPoint = 15, kLine = 1, kTriangle = 2;

/// Gmsh's name of an element type (the MSH format's table), for the message that refuses it.
std::string type_name(long long type) {
  static const char* const names[] = {
      nullptr,
      "a 2-node line",
      "a 3-node triangle",
      "a 4-node quadrangle",
      "a 4-node tetrahedron",
      "an 8-node hexahedron",
      "a 6-node prism",
      "a 5-node pyramid",
      "a 3-node second-order line",
      "a 6-node second-order triangle",
      "a 9-node second-order quadrangle",
      "a 10-node second-order tetrahedron",
      "a 27-node second-order hexahedron",
      "an 18-node second-order prism",
      "a 14-node second-order pyramid",
      "a 1-node point",
      "an 8-node second-order quadrangle",
      "a 20-node second-order hexahedron",
      "a 15-node second-order prism",
      "a 13-node second-order pyramid",
      "a 9-node third-order incomplete triangle",
      "a 10-node third-order triangle",
  };
  if (type > 0 && type < static_cast<long long>(std::size(names))) return names[type];
  return "an element";
}

/// A field of the file as it may appear in a one-line message: shortened, control characters (binary data) as '?'.
std::string quote(std::string_view s) {
  std::string r = "\"";
  for (std::size_t i = 0; i < s.size() && i < 40; ++i) r += static_cast<unsigned char>(s[i]) < 0x20 ? '?' : s[i];
  return r + (s.size() > 40 ? "...\"" : "\"");
}

std::string show(double x) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, x);
  return ec == std::errc{} ? std::string(buf, end) : "?";
}

/// The file, line by line, each split into whitespace-separated fields; knows its path and line number for messages.
class Lines {
 public:
  explicit Lines(const std::string& path) : path_(path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) fail_file("cannot open (is a directory)");
    in_.open(path, std::ios::binary);
    if (!in_) fail_file(std::string("cannot open (") + std::strerror(errno) + ")");
    const auto size = std::filesystem::file_size(path, ec);
    size_ = ec ? std::numeric_limits<std::uintmax_t>::max() : size;  // a pipe: no bound from the size
  }

  /// The next line's fields (blank lines are skipped); false at the end of the file.
  bool next() {
    while (std::getline(in_, text_)) {
      ++line_;
      if (!text_.empty() && text_.back() == '\r') text_.pop_back();  // a file written on Windows
      fields_.clear();
      for (std::size_t i = 0; i < text_.size();) {
        while (i < text_.size() && (text_[i] == ' ' || text_[i] == '\t')) ++i;
        const std::size_t start = i;
        while (i < text_.size() && text_[i] != ' ' && text_[i] != '\t') ++i;
        if (i > start) fields_.emplace_back(text_.data() + start, i - start);
      }
      if (!fields_.empty()) return true;
    }
    if (in_.bad()) fail_file(std::string("cannot read (") + std::strerror(errno) + ")");
    return false;
  }
  /// The next line, which must exist and have `count` fields (or at least `count`, when `at_least`).
  void expect(std::size_t count, const std::string& what, bool at_least = false) {
    if (!next()) fail_file("ends at line " + std::to_string(line_) + " (truncated?), where " + what + " was expected");
    if (fields_.size() < count || (!at_least && fields_.size() > count))
      fail("expected " + what + ", found " + std::to_string(fields_.size()) + " fields");
  }
  /// The next line, which must be exactly `marker` (a section's end).
  void expect_marker(const std::string& marker) {
    if (!next())
      fail_file("ends at line " + std::to_string(line_) + " (truncated?), where " + marker + " was expected");
    if (fields_.size() != 1 || fields_[0] != marker) fail("expected " + marker + ", found " + quote(text_));
  }

  std::size_t size() const { return fields_.size(); }
  std::string_view field(std::size_t k) const { return fields_[k]; }
  long long integer(std::size_t k, const char* what) const {
    long long v = 0;
    const auto s = fields_[k];
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc{} || end != s.data() + s.size())
      fail(std::string(what) + " " + quote(s) + " is not an integer");
    return v;
  }
  double real(std::size_t k, const char* what) const {
    double v = 0;
    const auto s = fields_[k];
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc{} || end != s.data() + s.size() || !std::isfinite(v))
      fail(std::string(what) + " " + quote(s) + " is not a finite number");
    return v;
  }
  /// A count of nodes or elements: not negative, and no more than the file can hold.
  long long count(std::size_t k, const char* what) const {
    const long long n = integer(k, what);
    if (n < 0) fail(std::string(what) + " is negative (" + std::to_string(n) + ")");
    if (static_cast<std::uintmax_t>(n) > size_ / kMinBytesPerItem || n > std::numeric_limits<int>::max())
      fail(std::string(what) + " " + std::to_string(n) + " is more than a file of " + std::to_string(size_) +
           " bytes can hold");
    return n;
  }

  std::size_t line() const { return line_; }
  const std::string& path() const { return path_; }
  [[noreturn]] void fail(const std::string& what) const { fail_at(line_, what); }
  [[noreturn]] void fail_at(std::size_t line, const std::string& what) const {
    fail_file("line " + std::to_string(line) + ": " + what);
  }
  [[noreturn]] void fail_file(const std::string& what) const { throw SceneError(path_ + ": " + what); }

 private:
  std::string path_;
  std::ifstream in_;
  std::uintmax_t size_ = 0;
  std::string text_;
  std::vector<std::string_view> fields_;
  std::size_t line_ = 0;
};

/// What the file holds, with each node's and triangle's Gmsh number and line for messages.
struct MshContent {
  Point2 box{};
  int version = 0;  // 2 or 4
  bool have_nodes = false, have_elements = false;
  std::vector<Point2> nodes;
  std::vector<long long> node_tags;
  std::vector<std::size_t> node_lines;
  std::unordered_map<long long, int> node_of_tag;
  std::vector<std::array<int, 3>> triangles;
  std::vector<long long> triangle_tags;
  std::vector<std::size_t> triangle_lines;
};

// ---------------------------------------------------------------------------------------------------------
// $MeshFormat

/// Reads "$MeshFormat / version file-type data-size / $EndMeshFormat" and returns the major version (2 or 4).
int read_format(Lines& in) {
  if (!in.next()) in.fail_file("is empty: expected a Gmsh mesh starting with $MeshFormat");
  if (in.field(0) == "$NOD" || in.field(0) == "$NOE")
    in.fail("this is Gmsh's MSH 1 format; re-export it as MSH 2.2 ASCII (gmsh -format msh22)");
  if (in.field(0) != "$MeshFormat") in.fail("expected $MeshFormat (a Gmsh .msh file), found " + quote(in.field(0)));
  in.expect(3, "the format line \"version file-type data-size\" (e.g. \"2.2 0 8\")");
  const std::string_view version = in.field(0);
  if (in.field(1) != "0") {
    if (in.field(1) == "1")
      in.fail("the mesh is in Gmsh's binary format, which is not supported; re-export it as ASCII, e.g. "
              "gmsh mesh.geo -2 -format msh22 (or in the GUI: File > Export, Gmsh MSH, ASCII, version 2)");
    in.fail("file-type " + quote(in.field(1)) + " is neither 0 (ASCII) nor 1 (binary)");
  }
  int major = 0;
  if (version == "2.2") major = 2;
  else if (version == "4.1") major = 4;
  else in.fail("MSH version " + quote(version) + " is not supported; expected 2.2 or 4.1 (gmsh -format msh22)");
  in.expect_marker("$EndMeshFormat");
  return major;
}

// ---------------------------------------------------------------------------------------------------------
// $Nodes

/// Records node `tag` at (x, y, z), read on the current line, after checking that it is new and in the box's plane.
void add_node(Lines& in, MshContent& m, long long tag, double x, double y, double z) {
  if (tag <= 0) in.fail("node number " + std::to_string(tag) + " is not positive");
  const auto [it, fresh] = m.node_of_tag.try_emplace(tag, static_cast<int>(m.nodes.size()));
  if (!fresh)
    in.fail("node " + std::to_string(tag) + " is defined twice (first on line " +
            std::to_string(m.node_lines[it->second]) + ")");
  const double size = std::max(m.box[0], m.box[1]);
  if (std::abs(z) > 1e-12 * size)
    in.fail("node " + std::to_string(tag) + " has z = " + show(z) + "; expected a plane mesh at z = 0");
  // the TriangleMesh constructor's tolerance, checked here to name the node by its Gmsh number
  const double tol = 1e-9 * size;
  if (x < -tol || x > m.box[0] + tol || y < -tol || y > m.box[1] + tol)
    in.fail("node " + std::to_string(tag) + " at (" + show(x) + ", " + show(y) + ") lies outside the domain box [0, " +
            show(m.box[0]) + "] x [0, " + show(m.box[1]) + "] (grid.length)");
  m.nodes.push_back({x, y});
  m.node_tags.push_back(tag);
  m.node_lines.push_back(in.line());
}

/// MSH 2.2: a count, then "tag x y z" lines.
void read_nodes_v2(Lines& in, MshContent& m) {
  in.expect(1, "the number of nodes");
  const long long n = in.count(0, "the number of nodes");
  m.nodes.reserve(n);
  for (long long i = 0; i < n; ++i) {
    in.expect(4, "node " + std::to_string(i + 1) + " of " + std::to_string(n) + " as \"number x y z\"");
    add_node(in, m, in.integer(0, "node number"), in.real(1, "x"), in.real(2, "y"), in.real(3, "z"));
  }
}

/// MSH 4.1: "blocks nodes min-tag max-tag", then per block "dim entity parametric count", its tags (one a line),
/// then its coordinates (x y z, and u [v] when parametric).
void read_nodes_v4(Lines& in, MshContent& m) {
  in.expect(4, "\"numEntityBlocks numNodes minNodeTag maxNodeTag\"");
  const long long blocks = in.count(0, "the number of node blocks"), n = in.count(1, "the number of nodes");
  m.nodes.reserve(n);
  long long read = 0;
  std::vector<long long> tags;
  for (long long b = 0; b < blocks; ++b) {
    in.expect(4, "a node block header \"entityDim entityTag parametric numNodesInBlock\"");
    const long long dim = in.integer(0, "the entity dimension"), parametric = in.integer(2, "the parametric flag");
    const long long count = in.count(3, "the number of nodes in the block");
    if (count > n - read)
      in.fail("the node blocks hold more nodes than the " + std::to_string(n) + " that $Nodes announces");
    if (dim < 0 || dim > 3 || (parametric != 0 && parametric != 1))
      in.fail("expected an entity dimension 0-3 and a parametric flag 0 or 1");
    tags.clear();
    for (long long i = 0; i < count; ++i) {
      in.expect(1, "a node number");
      tags.push_back(in.integer(0, "node number"));
    }
    const std::size_t fields = 3 + (parametric ? dim : 0);
    for (long long i = 0; i < count; ++i) {
      in.expect(fields, "the coordinates of node " + std::to_string(tags[i]) + " (" + std::to_string(fields) +
                            " numbers)");
      add_node(in, m, tags[i], in.real(0, "x"), in.real(1, "y"), in.real(2, "z"));
    }
    read += count;
  }
  if (read != n)
    in.fail("the node blocks hold " + std::to_string(read) + " nodes, but $Nodes announces " + std::to_string(n));
}

// ---------------------------------------------------------------------------------------------------------
// $Elements

/// Keeps a triangle, skips a point or line (Gmsh's boundary entities), refuses anything else.
void add_element(Lines& in, MshContent& m, long long tag, long long type, std::size_t first_node) {
  if (type == kPoint || type == kLine) return;
  if (type != kTriangle)
    in.fail("element " + std::to_string(tag) + " is " + type_name(type) + " (Gmsh type " + std::to_string(type) +
            "); only 3-node triangles (type 2) are supported");
  std::array<int, 3> t{};
  for (int k = 0; k < 3; ++k) {
    const long long node = in.integer(first_node + k, "node number");
    const auto it = m.node_of_tag.find(node);
    if (it == m.node_of_tag.end())
      in.fail("element " + std::to_string(tag) + " names node " + std::to_string(node) +
              ", which $Nodes does not define");
    t[k] = it->second;
  }
  m.triangles.push_back(t);
  m.triangle_tags.push_back(tag);
  m.triangle_lines.push_back(in.line());
}

/// The number of nodes of the element types that are read (kept or skipped); 0 for the others.
std::size_t nodes_of(long long type) { return type == kPoint ? 1 : type == kLine ? 2 : type == kTriangle ? 3 : 0; }

/// MSH 2.2: a count, then "number type ntags tag... node..." lines.
void read_elements_v2(Lines& in, MshContent& m) {
  in.expect(1, "the number of elements");
  const long long n = in.count(0, "the number of elements");
  for (long long i = 0; i < n; ++i) {
    in.expect(3, "element " + std::to_string(i + 1) + " of " + std::to_string(n) +
                     " as \"number type ntags tags... nodes...\"", true);
    const long long tag = in.integer(0, "element number"), type = in.integer(1, "element type");
    const long long ntags = in.integer(2, "the number of tags");
    if (ntags < 0 || static_cast<std::size_t>(ntags) > in.size() - 3)
      in.fail("element " + std::to_string(tag) + " announces " + std::to_string(ntags) + " tags, but the line has " +
              std::to_string(in.size() - 3) + " fields after them");
    const std::size_t first_node = 3 + ntags;
    if (nodes_of(type) != 0 && in.size() - first_node != nodes_of(type))
      in.fail("element " + std::to_string(tag) + " (" + type_name(type) + ") has " +
              std::to_string(in.size() - first_node) + " nodes; expected " + std::to_string(nodes_of(type)));
    add_element(in, m, tag, type, first_node);
  }
}

/// MSH 4.1: "blocks elements min-tag max-tag", then per block "dim entity type count" and "number node..." lines.
void read_elements_v4(Lines& in, MshContent& m) {
  in.expect(4, "\"numEntityBlocks numElements minElementTag maxElementTag\"");
  const long long blocks = in.count(0, "the number of element blocks"), n = in.count(1, "the number of elements");
  long long read = 0;
  for (long long b = 0; b < blocks; ++b) {
    in.expect(4, "an element block header \"entityDim entityTag elementType numElementsInBlock\"");
    const long long type = in.integer(2, "element type"), count = in.count(3, "the number of elements in the block");
    if (count > n - read)
      in.fail("the element blocks hold more elements than the " + std::to_string(n) + " that $Elements announces");
    for (long long i = 0; i < count; ++i) {
      // a refused type is named with its first element's number, read before the node count is checked
      in.expect(1, "an element as \"number nodes...\"", true);
      const long long tag = in.integer(0, "element number");
      if (nodes_of(type) != 0 && in.size() - 1 != nodes_of(type))
        in.fail("element " + std::to_string(tag) + " (" + type_name(type) + ") has " + std::to_string(in.size() - 1) +
                " nodes; expected " + std::to_string(nodes_of(type)));
      add_element(in, m, tag, type, 1);
    }
    read += count;
  }
  if (read != n)
    in.fail("the element blocks hold " + std::to_string(read) + " elements, but $Elements announces " +
            std::to_string(n));
}

// ---------------------------------------------------------------------------------------------------------
// The whole file

/// Reads the sections; those other than $Nodes and $Elements ($PhysicalNames, $Entities, ...) are skipped.
void read_sections(Lines& in, MshContent& m) {
  while (in.next()) {
    const std::string name(in.field(0));
    if (in.size() != 1 || name.size() < 2 || name[0] != '$' || name.compare(0, 4, "$End") == 0)
      in.fail("expected a section such as $Nodes or $Elements, found " + quote(name));
    if (name == "$Nodes") {
      if (m.have_nodes) in.fail("a second $Nodes section; expected one");
      m.have_nodes = true;
      if (m.version == 2) read_nodes_v2(in, m);
      else read_nodes_v4(in, m);
      in.expect_marker("$EndNodes");
    } else if (name == "$Elements") {
      if (!m.have_nodes) in.fail("$Elements before $Nodes; expected the nodes first");
      if (m.have_elements) in.fail("a second $Elements section; expected one");
      m.have_elements = true;
      if (m.version == 2) read_elements_v2(in, m);
      else read_elements_v4(in, m);
      in.expect_marker("$EndElements");
    } else {
      const std::string end = "$End" + name.substr(1);
      const std::size_t start = in.line();
      bool closed = false;
      while (!closed && in.next()) closed = in.size() == 1 && in.field(0) == end;
      if (!closed) in.fail_at(start, "section " + quote(name) + " is not closed by " + end);
    }
  }
  if (!m.have_nodes) in.fail_file("has no $Nodes section; expected the mesh's nodes");
  if (!m.have_elements) in.fail_file("has no $Elements section; expected the mesh's triangles");
  if (m.triangles.empty())
    in.fail_file("has no triangles (Gmsh type 2); expected a 2D mesh (gmsh -2; if the .geo defines physical groups, "
                 "Gmsh saves only their elements: put the surface in one, or export with -save_all)");
}

/// What the TriangleMesh constructor refuses about a triangle, checked by Gmsh number: orientation, area, and at most
/// two triangles on an edge, on opposite sides of it (two on one side overlap: e.g. a duplicated element).
void check_triangles(const Lines& in, const MshContent& m) {
  const double min_area = 1e-12 * m.box[0] * m.box[1];
  const auto element = [&](std::size_t e) { return "element " + std::to_string(m.triangle_tags[e]); };
  for (std::size_t e = 0; e < m.triangles.size(); ++e) {
    const Point2 &a = m.nodes[m.triangles[e][0]], &b = m.nodes[m.triangles[e][1]], &c = m.nodes[m.triangles[e][2]];
    const double area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
    if (area < -min_area)
      in.fail_at(m.triangle_lines[e], element(e) + " is inverted (its nodes run clockwise, area " + show(area) +
                                          "); expected counter-clockwise triangles, as Gmsh writes for a surface "
                                          "whose normal is +z");
    if (area <= min_area)
      in.fail_at(m.triangle_lines[e], element(e) + " is degenerate (area " + show(area) +
                                          "); expected an area above 1e-12 of the box's");
  }
  // each edge (lower node, higher node) → the triangles on it: the one where it runs upwards, and the other
  struct Sides {
    int up = -1, down = -1;
  };
  std::unordered_map<std::uint64_t, Sides> edges;
  edges.reserve(2 * m.triangles.size());
  for (std::size_t e = 0; e < m.triangles.size(); ++e)
    for (int k = 0; k < 3; ++k) {
      const int p = m.triangles[e][k], q = m.triangles[e][(k + 1) % 3];
      const std::uint64_t key =
          (static_cast<std::uint64_t>(std::min(p, q)) << 32) | static_cast<std::uint32_t>(std::max(p, q));
      Sides& s = edges[key];
      int& side = p < q ? s.up : s.down;
      const auto edge = "the edge of nodes " + std::to_string(m.node_tags[p]) + "-" + std::to_string(m.node_tags[q]);
      if (side >= 0 && (p < q ? s.down : s.up) >= 0)
        in.fail_at(m.triangle_lines[e], element(e) + " is a third triangle on " + edge + " (with " + element(s.up) +
                                            " and " + element(s.down) + "); expected a manifold mesh");
      if (side >= 0)
        in.fail_at(m.triangle_lines[e], element(e) + " overlaps " + element(side) + ": both lie on the same side of " +
                                            edge + " (a duplicated element?)");
      side = static_cast<int>(e);
    }
}

/// The nodes that some triangle uses, renumbered in file order: a node of no triangle (a stray geometry point) would
/// carry no mass.
void drop_unused_nodes(MshContent& m) {
  std::vector<int> index(m.nodes.size(), -1);
  for (const auto& t : m.triangles)
    for (int v : t) index[v] = 0;
  std::vector<Point2> kept;
  for (std::size_t i = 0; i < m.nodes.size(); ++i)
    if (index[i] == 0) {
      index[i] = static_cast<int>(kept.size());
      kept.push_back(m.nodes[i]);
    }
  for (auto& t : m.triangles)
    for (int& v : t) v = index[v];
  m.nodes = std::move(kept);
}

}  // namespace

TriangleMesh read_gmsh(const std::string& path, Point2 box) {
  // checked first: every node would otherwise be "outside" a box that is not one
  if (!(box[0] > 0 && box[1] > 0 && std::isfinite(box[0]) && std::isfinite(box[1])))
    throw SceneError(path + ": the domain box (grid.length) must be positive, found [" + show(box[0]) + ", " +
                     show(box[1]) + "]");
  Lines in(path);
  MshContent m;
  m.box = box;
  m.version = read_format(in);
  read_sections(in, m);
  check_triangles(in, m);
  drop_unused_nodes(m);
  return TriangleMesh(std::move(m.nodes), std::move(m.triangles), box, path);
}

}  // namespace mpm
