// The triangular background mesh (engine/triangle_mesh.hpp): the Gmsh reader on good and bad files (every refusal
// names the file and the line or Gmsh element), and the mesh's geometry, point location, neighbours, colouring and
// side flags, each checked against a brute-force computation done here.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "engine/scene.hpp"
#include "engine/triangle_mesh.hpp"

using namespace mpm;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

namespace {

std::string test_mesh(const std::string& name) { return std::string(MPM_SOURCE_DIR) + "/tests/meshes/" + name; }
std::string tool_mesh(const std::string& name) { return std::string(MPM_SOURCE_DIR) + "/tools/meshes/" + name; }

/// The message of the SceneError that reading `path` throws; any other exception fails the test.
std::string read_error(const std::string& path, Point2 box = {1, 1}) {
  try {
    read_gmsh(path, box);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(no error)";
}

/// A file of the given text in the temporary directory, for variations too small to keep as files.
std::string temp_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("mpm_test_triangle_mesh_" + name);
  std::ofstream(path, std::ios::binary) << text;
  return path.string();
}

/// The valid hand-written mesh of tests/meshes/square_tags.msh, with its node and element sections replaceable.
const std::string kFormat = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
const std::string kNodes =
    "$Nodes\n9\n10 0 0 0\n20 0.5 0 0\n30 1 0 0\n40 0 0.5 0\n50 0.5 0.5 0\n60 1 0.5 0\n70 0 1 0\n80 0.5 1 0\n"
    "90 1 1 0\n$EndNodes\n";
const std::string kElements =
    "$Elements\n8\n11 2 2 0 1 10 20 50\n12 2 2 0 1 10 50 40\n13 2 2 0 1 20 30 60\n14 2 2 0 1 20 60 50\n"
    "15 2 2 0 1 40 50 80\n16 2 2 0 1 40 80 70\n17 2 2 0 1 50 60 90\n18 2 2 0 1 50 90 80\n$EndElements\n";

double signed_area(const Point2& a, const Point2& b, const Point2& c) {
  return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
}

/// Barycentric coordinates by sub-areas, independent of TriangleMesh::barycentric.
std::array<double, 3> brute_barycentric(const TriangleMesh& mesh, std::size_t e, const Point2& x) {
  const auto& t = mesh.triangle(e);
  const Point2 &a = mesh.nodes()[t[0]], &b = mesh.nodes()[t[1]], &c = mesh.nodes()[t[2]];
  const double area = signed_area(a, b, c);
  return {signed_area(x, b, c) / area, signed_area(a, x, c) / area, signed_area(a, b, x) / area};
}

double total_area(const TriangleMesh& mesh) {
  double sum = 0;
  for (std::size_t e = 0; e < mesh.triangle_count(); ++e) sum += mesh.area(e);
  return sum;
}

/// The meshes the class tests run on: Gmsh's unstructured squares and jittered meshes of a non-square box.
std::vector<TriangleMesh> sample_meshes() {
  std::vector<TriangleMesh> meshes;
  meshes.push_back(read_gmsh(test_mesh("square_small.msh"), {1, 1}));
  meshes.push_back(read_gmsh(tool_mesh("unit_square_coarse.msh"), {1, 1}));
  meshes.push_back(read_gmsh(tool_mesh("plate_1058.msh"), {1, 1}));
  meshes.push_back(make_jittered_mesh({2.0, 0.5}, 13, 5, 0.2, 7));
  meshes.push_back(make_jittered_mesh({1.0, 3.0}, 4, 17, 0.0, 1));
  return meshes;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------
// The reader on good files

TEST_CASE("read_gmsh reads Gmsh's 2.2 mesh of the square, skipping its points and lines", "[mesh]") {
  const auto mesh = read_gmsh(test_mesh("square_small.msh"), {1, 1});
  CHECK(mesh.node_count() == 30);
  CHECK(mesh.triangle_count() == 42);  // the file's 62 elements less 4 points and 16 lines
  CHECK(mesh.origin() == test_mesh("square_small.msh"));
  CHECK(total_area(mesh) == Approx(1.0).epsilon(1e-12));
  // node 17 of the file, the first interior one, is index 16
  CHECK(mesh.nodes()[16][0] == 0.3640932128841505);
  CHECK(mesh.nodes()[16][1] == 0.7867687832230461);
}

TEST_CASE("read_gmsh reads the 4.1 file of the same mesh into the same nodes and triangles", "[mesh]") {
  const auto v2 = read_gmsh(test_mesh("square_small.msh"), {1, 1});
  const auto v4 = read_gmsh(test_mesh("square_small_v41.msh"), {1, 1});
  CHECK(v4.node_count() == v2.node_count());
  CHECK(v4.nodes() == v2.nodes());
  CHECK(v4.triangles() == v2.triangles());
}

TEST_CASE("read_gmsh maps non-contiguous node numbers to indices in file order", "[mesh]") {
  const auto mesh = read_gmsh(test_mesh("square_tags.msh"), {1, 1});
  REQUIRE(mesh.node_count() == 9);
  REQUIRE(mesh.triangle_count() == 8);
  CHECK(mesh.nodes()[4] == Point2{0.5, 0.5});  // node 50
  CHECK(mesh.nodes()[8] == Point2{1, 1});      // node 90
  CHECK(mesh.triangle(0) == std::array<int, 3>{0, 1, 4});  // element 11: nodes 10 20 50
  CHECK(mesh.triangle(7) == std::array<int, 3>{4, 8, 7});  // element 18: nodes 50 90 80
  for (std::size_t e = 0; e < 8; ++e) CHECK(mesh.area(e) == Approx(0.125));
}

TEST_CASE("read_gmsh reads the committed meshes of tools/meshes with their triangle counts", "[mesh]") {
  const std::map<std::string, std::size_t> counts{{"unit_square_coarse.msh", 162}, {"plate_1058.msh", 1056},
                                                  {"plate_h1.msh", 246},           {"plate_h2.msh", 946},
                                                  {"plate_h3.msh", 3708}};
  for (const auto& [name, count] : counts) {
    INFO(name);
    const auto mesh = read_gmsh(tool_mesh(name), {1, 1});
    CHECK(mesh.triangle_count() == count);
    CHECK(total_area(mesh) == Approx(1.0).epsilon(1e-12));
  }
}

TEST_CASE("read_gmsh accepts Windows line ends, blank lines and unknown sections", "[mesh]") {
  std::string text = kFormat + "\n$Entities\nanything at all\n$EndEntities\n" + kNodes + "\n" + kElements +
                     "$NodeData\n1\n\"u\"\n$EndNodeData\n";
  std::string crlf;
  for (char c : text) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  const auto mesh = read_gmsh(temp_file("crlf.msh", crlf), {1, 1});
  CHECK(mesh.triangle_count() == 8);
  CHECK(mesh.node_count() == 9);
}

TEST_CASE("read_gmsh drops nodes that no triangle uses", "[mesh]") {
  // node 99 is a stray geometry point: it would be a node of no mass
  std::string nodes = kNodes;
  nodes.replace(nodes.find("9\n10 0 0 0"), 10, "10\n10 0 0 0\n99 0.25 0.25 0");
  const auto mesh = read_gmsh(temp_file("stray.msh", kFormat + nodes + kElements), {1, 1});
  CHECK(mesh.node_count() == 9);
  CHECK(mesh.nodes()[1] == Point2{0.5, 0});  // node 20, after the dropped 99
  CHECK(mesh.triangle(0) == std::array<int, 3>{0, 1, 4});
}

TEST_CASE("read_gmsh reads a mesh of a box of another size", "[mesh]") {
  // the square's mesh stretched to [0, 2] x [0, 1]
  std::string nodes = kNodes;
  for (const auto& [from, to] : {std::pair{"20 0.5 0 0", "20 1 0 0"}, {"30 1 0 0", "30 2 0 0"},
                                 {"50 0.5 0.5 0", "50 1 0.5 0"}, {"60 1 0.5 0", "60 2 0.5 0"},
                                 {"80 0.5 1 0", "80 1 1 0"}, {"90 1 1 0", "90 2 1 0"}})
    nodes.replace(nodes.find(from), std::string(from).size(), to);
  const auto mesh = read_gmsh(temp_file("box.msh", kFormat + nodes + kElements), {2, 1});
  CHECK(total_area(mesh) == Approx(2.0));
  CHECK(mesh.on_side(2, 1));        // node 30 at x = 2
  CHECK_FALSE(mesh.on_side(1, 1));  // node 20 at x = 1
  // in the unit box, node 30 lies outside
  CHECK_THAT(read_error(temp_file("box.msh", kFormat + nodes + kElements), {1, 1}),
             Contains("line 8") && Contains("node 30 at (2, 0)"));
}

// ---------------------------------------------------------------------------------------------------------
// The reader on bad files: each message starts with the path and names the element or line

TEST_CASE("read_gmsh refuses a quadrangle naming its Gmsh element number", "[mesh]") {
  const auto path = test_mesh("bad_quad.msh");
  REQUIRE_THROWS_AS(read_gmsh(path, {1, 1}), SceneError);
  REQUIRE_THROWS_WITH(read_gmsh(path, {1, 1}),
                      StartsWith(path) && Contains("line 26") &&
                          Contains("element 17 is a 4-node quadrangle (Gmsh type 3); only 3-node triangles (type 2) "
                                   "are supported"));
}

TEST_CASE("read_gmsh refuses an inverted triangle naming its Gmsh element number", "[mesh]") {
  const auto path = test_mesh("bad_inverted.msh");
  CHECK_THAT(read_error(path), StartsWith(path) && Contains("line 26") && Contains("element 17 is inverted") &&
                                   Contains("counter-clockwise"));
}

TEST_CASE("read_gmsh refuses a degenerate triangle naming its Gmsh element number", "[mesh]") {
  const auto path = test_mesh("bad_degenerate.msh");
  CHECK_THAT(read_error(path), StartsWith(path) && Contains("line 28") && Contains("element 19 is degenerate"));
}

TEST_CASE("read_gmsh refuses a third triangle on an edge naming the three elements and the edge's nodes", "[mesh]") {
  const auto path = test_mesh("bad_nonmanifold.msh");
  CHECK_THAT(read_error(path), StartsWith(path) && Contains("line 28") && Contains("element 19 is a third triangle") &&
                                   Contains("element 14") && Contains("element 17") && Contains("nodes 60-50") &&
                                   Contains("manifold"));
}

TEST_CASE("read_gmsh refuses a duplicated triangle as an overlap", "[mesh]") {
  std::string elements = kElements;
  elements.replace(elements.find("$Elements\n8\n"), 12, "$Elements\n9\n");
  elements.replace(elements.find("$EndElements"), 12, "19 2 2 0 1 10 20 50\n$EndElements");
  CHECK_THAT(read_error(temp_file("dup.msh", kFormat + kNodes + elements)),
             Contains("line 26") && Contains("element 19 overlaps element 11") && Contains("nodes 10-20"));
  // a duplicate of an interior triangle is a third one on its first edge
  elements.replace(elements.find("19 2 2 0 1 10 20 50"), 19, "19 2 2 0 1 40 50 80");
  CHECK_THAT(read_error(temp_file("dup2.msh", kFormat + kNodes + elements)),
             Contains("element 19 is a third triangle on the edge of nodes 40-50 (with element 15 and element 12)"));
}

TEST_CASE("read_gmsh refuses a node outside the box naming its Gmsh number and line", "[mesh]") {
  const auto path = test_mesh("bad_outside.msh");
  CHECK_THAT(read_error(path), StartsWith(path) && Contains("line 14") && Contains("node 90 at (1.5, 1)") &&
                                   Contains("outside the domain box"));
  // the good mesh in a smaller box: its first node beyond x = 0.75
  CHECK_THAT(read_error(test_mesh("square_tags.msh"), {0.75, 1}), Contains("line 12") && Contains("node 30"));
}

TEST_CASE("read_gmsh refuses a node off the plane z = 0", "[mesh]") {
  const auto path = test_mesh("bad_z.msh");
  CHECK_THAT(read_error(path), StartsWith(path) && Contains("line 10") && Contains("node 50 has z = 0.1"));
}

TEST_CASE("read_gmsh refuses an element naming an undefined node", "[mesh]") {
  const auto path = test_mesh("bad_unknown_node.msh");
  CHECK_THAT(read_error(path), StartsWith(path) && Contains("line 31") && Contains("element 18 names node 99"));
}

TEST_CASE("read_gmsh refuses a truncated file naming where it ends", "[mesh]") {
  const auto path = test_mesh("bad_truncated.msh");
  CHECK_THAT(read_error(path), StartsWith(path) && Contains("ends at line 24") && Contains("truncated") &&
                                   Contains("element 4 of 10"));
  // cut inside $Nodes, and just before $EndElements
  const std::string whole = kFormat + kNodes + kElements;
  CHECK_THAT(read_error(temp_file("cut1.msh", whole.substr(0, whole.find("60 1 0.5 0")))),
             Contains("ends at line 10") && Contains("node 6 of 9"));
  CHECK_THAT(read_error(temp_file("cut2.msh", whole.substr(0, whole.find("$EndElements")))),
             Contains("ends at line 25") && Contains("$EndElements"));
}

TEST_CASE("read_gmsh refuses a binary file, telling how to re-export it as ASCII", "[mesh]") {
  const auto path = test_mesh("bad_binary.msh");
  CHECK_THAT(read_error(path), StartsWith(path) && Contains("line 2") && Contains("binary") &&
                                   Contains("-format msh22"));
}

TEST_CASE("read_gmsh refuses a file without nodes", "[mesh]") {
  const auto path = test_mesh("bad_missing_nodes.msh");
  CHECK_THAT(read_error(path), StartsWith(path) && Contains("line 4") && Contains("$Nodes"));
  CHECK_THAT(read_error(temp_file("format_only.msh", kFormat)), Contains("no $Nodes section"));
  CHECK_THAT(read_error(temp_file("nodes_only.msh", kFormat + kNodes)), Contains("no $Elements section"));
  const std::string points = "$Elements\n1\n1 15 2 0 1 10\n$EndElements\n";
  CHECK_THAT(read_error(temp_file("no_triangles.msh", kFormat + kNodes + points)), Contains("no triangles"));
}

TEST_CASE("read_gmsh refuses missing and unreadable files", "[mesh]") {
  const auto missing = test_mesh("no_such_file.msh");
  CHECK(read_error(missing) == missing + ": cannot open (No such file or directory)");
  const auto dir = test_mesh("");
  CHECK_THAT(read_error(dir), StartsWith(dir) && Contains("is a directory"));
  CHECK_THAT(read_error(temp_file("empty.msh", "")), Contains("is empty"));
  CHECK_THAT(read_error(temp_file("json.msh", "{\"grid\": 1}\n")), Contains("line 1") && Contains("$MeshFormat"));
}

TEST_CASE("read_gmsh refuses other versions and malformed lines, naming the line", "[mesh]") {
  CHECK_THAT(read_error(temp_file("v1.msh", "$NOD\n1\n1 0 0 0\n$ENDNOD\n")), Contains("line 1") && Contains("MSH 1"));
  CHECK_THAT(read_error(temp_file("v40.msh", "$MeshFormat\n4 0 8\n$EndMeshFormat\n")),
             Contains("line 2") && Contains("version \"4\" is not supported"));
  CHECK_THAT(read_error(temp_file("fmt.msh", "$MeshFormat\n2.2 0 8\n$EndNodes\n")),
             Contains("line 3") && Contains("expected $EndMeshFormat"));
  std::string nodes = kNodes;
  nodes.replace(nodes.find("40 0 0.5 0"), 10, "40 0 zero 0");
  CHECK_THAT(read_error(temp_file("word.msh", kFormat + nodes + kElements)),
             Contains("line 9") && Contains("y \"zero\" is not a finite number"));
  nodes = kNodes;
  nodes.replace(nodes.find("40 0 0.5 0"), 10, "40 0 0.5");
  CHECK_THAT(read_error(temp_file("short.msh", kFormat + nodes + kElements)),
             Contains("line 9") && Contains("number x y z"));
  nodes = kNodes;
  nodes.replace(nodes.find("40 0 0.5 0"), 10, "20 0 0.5 0");
  CHECK_THAT(read_error(temp_file("twice.msh", kFormat + nodes + kElements)),
             Contains("line 9") && Contains("node 20 is defined twice (first on line 7)"));
  std::string elements = kElements;
  elements.replace(elements.find("13 2 2 0 1 20 30 60"), 19, "13 2 2 0 1 20 30");
  CHECK_THAT(read_error(temp_file("two_nodes.msh", kFormat + kNodes + elements)),
             Contains("line 20") && Contains("element 13") && Contains("has 2 nodes; expected 3"));
  CHECK_THAT(read_error(temp_file("stray_line.msh", kFormat + "hello\n" + kNodes + kElements)),
             Contains("line 4") && Contains("\"hello\""));
  CHECK_THAT(read_error(temp_file("open_section.msh", kFormat + "$Comments\nsome text\n")),
             Contains("line 4") && Contains("not closed by $EndComments"));
}

TEST_CASE("read_gmsh refuses a count larger than the file before allocating for it", "[mesh]") {
  std::string nodes = kNodes;
  nodes.replace(nodes.find("$Nodes\n9\n"), 9, "$Nodes\n4000000000000000000\n");
  CHECK_THAT(read_error(temp_file("huge.msh", kFormat + nodes + kElements)),
             Contains("line 5") && Contains("more than a file of"));
  nodes.replace(nodes.find("4000000000000000000"), 19, "-3");
  CHECK_THAT(read_error(temp_file("negative.msh", kFormat + nodes + kElements)), Contains("negative"));
  std::string elements = kElements;
  elements.replace(elements.find("$Elements\n8\n"), 12, "$Elements\n100000\n");
  CHECK_THAT(read_error(temp_file("many.msh", kFormat + kNodes + elements)), Contains("more than a file of"));
}

TEST_CASE("read_gmsh refuses a 4.1 block of quadrangles naming its first element", "[mesh]") {
  const std::string text = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                           "$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n$EndNodes\n"
                           "$Elements\n1 1 7 7\n2 1 3 1\n7 1 2 3 4\n$EndElements\n";
  CHECK_THAT(read_error(temp_file("quad41.msh", text)),
             Contains("line 19") && Contains("element 7 is a 4-node quadrangle (Gmsh type 3)"));
  // the same square as two triangles is read
  const std::string good = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                           "$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n$EndNodes\n"
                           "$Elements\n1 2 7 8\n2 1 2 2\n7 1 2 3\n8 1 3 4\n$EndElements\n";
  const auto mesh = read_gmsh(temp_file("tri41.msh", good), {1, 1});
  CHECK(mesh.triangle_count() == 2);
  CHECK(total_area(mesh) == Approx(1.0));
  // a block that claims more nodes than the section
  std::string over = good;
  over.replace(over.find("2 1 0 4"), 7, "2 1 0 5");
  CHECK_THAT(read_error(temp_file("over41.msh", over)), Contains("line 6") && Contains("more nodes than the 4"));
}

TEST_CASE("read_gmsh refuses a box that is not positive", "[mesh]") {
  CHECK_THAT(read_error(test_mesh("square_tags.msh"), {0, 1}), Contains("must be positive"));
  CHECK_THAT(read_error(test_mesh("square_tags.msh"), {1, std::nan("")}), Contains("must be positive"));
}

// ---------------------------------------------------------------------------------------------------------
// The TriangleMesh class

TEST_CASE("triangle areas are positive, match the nodes and sum to the box's area", "[mesh]") {
  for (const auto& mesh : sample_meshes()) {
    INFO(mesh.origin());
    double sum = 0, min_height = std::numeric_limits<double>::infinity();
    for (std::size_t e = 0; e < mesh.triangle_count(); ++e) {
      const auto& t = mesh.triangle(e);
      const Point2 &a = mesh.nodes()[t[0]], &b = mesh.nodes()[t[1]], &c = mesh.nodes()[t[2]];
      const double area = signed_area(a, b, c);
      REQUIRE(area > 0);
      CHECK(mesh.area(e) == Approx(area).epsilon(1e-14));
      sum += area;
      // altitude onto each side: twice the area over the side's length
      for (const auto& [p, q] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}})
        min_height = std::min(min_height, 2 * area / std::hypot(q[0] - p[0], q[1] - p[1]));
    }
    CHECK(sum == Approx(mesh.box()[0] * mesh.box()[1]).epsilon(1e-12));
    CHECK(mesh.min_height() == Approx(min_height).epsilon(1e-12));
  }
}

TEST_CASE("locate finds the triangle that a brute-force scan finds, for random points", "[mesh]") {
  std::mt19937_64 rng(2024);
  for (const auto& mesh : sample_meshes()) {
    INFO(mesh.origin());
    std::uniform_real_distribution<double> ux(0, mesh.box()[0]), uy(0, mesh.box()[1]);
    int checked = 0;
    for (int i = 0; i < 5000; ++i) {
      const Point2 x{ux(rng), uy(rng)};
      std::vector<int> inside;  // the triangles that contain x, with a margin
      for (std::size_t e = 0; e < mesh.triangle_count(); ++e) {
        const auto l = brute_barycentric(mesh, e, x);
        if (std::min({l[0], l[1], l[2]}) > -1e-12) inside.push_back(static_cast<int>(e));
      }
      REQUIRE(!inside.empty());  // the mesh covers its box
      const int found = mesh.locate(x);
      INFO("x = (" << x[0] << ", " << x[1] << ")");
      if (inside.size() == 1) {  // clearly inside one triangle
        REQUIRE(found == inside[0]);
        ++checked;
      } else {
        REQUIRE(std::find(inside.begin(), inside.end(), found) != inside.end());
      }
      // its barycentric coordinates are the brute-force ones, and rebuild x
      const auto l = mesh.barycentric(found, x), b = brute_barycentric(mesh, found, x);
      for (int k = 0; k < 3; ++k) CHECK(l[k] == Approx(b[k]).margin(1e-12));
      CHECK(l[0] + l[1] + l[2] == Approx(1.0));
      for (int d = 0; d < 2; ++d) {
        double rebuilt = 0;
        for (int k = 0; k < 3; ++k) rebuilt += l[k] * mesh.nodes()[mesh.triangle(found)[k]][d];
        CHECK(rebuilt == Approx(x[d]).margin(1e-12));
      }
    }
    CHECK(checked > 4900);
  }
}

TEST_CASE("locate puts a point on a shared edge or node into the lowest-numbered triangle", "[mesh]") {
  for (const auto& mesh : sample_meshes()) {
    INFO(mesh.origin());
    std::vector<int> lowest_at_node(mesh.node_count(), std::numeric_limits<int>::max());
    for (std::size_t e = 0; e < mesh.triangle_count(); ++e)
      for (int v : mesh.triangle(e)) lowest_at_node[v] = std::min(lowest_at_node[v], static_cast<int>(e));
    for (std::size_t i = 0; i < mesh.node_count(); ++i) {
      INFO("node " << i);
      CHECK(mesh.locate(mesh.nodes()[i]) == lowest_at_node[i]);
    }
    // the midpoint of each interior edge: the lower of its two triangles
    for (std::size_t e = 0; e < mesh.triangle_count(); ++e)
      for (int k = 0; k < 3; ++k) {
        const int f = mesh.neighbour(e, k);
        const auto& t = mesh.triangle(e);
        const Point2 &p = mesh.nodes()[t[(k + 1) % 3]], &q = mesh.nodes()[t[(k + 2) % 3]];
        const Point2 mid{0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])};
        INFO("edge opposite vertex " << k << " of triangle " << e);
        CHECK(mesh.locate(mid) == (f < 0 ? static_cast<int>(e) : std::min(static_cast<int>(e), f)));
      }
  }
}

TEST_CASE("locate returns -1 for points outside the box", "[mesh]") {
  for (const auto& mesh : sample_meshes()) {
    INFO(mesh.origin());
    const double a = mesh.box()[0], b = mesh.box()[1], eps = 1e-9;
    for (const Point2& x : {Point2{-eps, 0.5 * b}, Point2{a + eps, 0.5 * b}, Point2{0.5 * a, -eps},
                            Point2{0.5 * a, b + eps}, Point2{-1, -1}, Point2{2 * a, 2 * b},
                            Point2{std::nan(""), 0.5 * b}, Point2{0.5 * a, std::numeric_limits<double>::infinity()}})
      CHECK(mesh.locate(x) == -1);
    // and finds the corners and the sides' midpoints
    for (const Point2& x : {Point2{0, 0}, Point2{a, 0}, Point2{a, b}, Point2{0, b}, Point2{0.5 * a, 0},
                            Point2{a, 0.5 * b}, Point2{0.5 * a, b}, Point2{0, 0.5 * b}})
      CHECK(mesh.locate(x) >= 0);
  }
}

TEST_CASE("neighbours are symmetric, share the edge, and boundary edges lie on the box's sides", "[mesh]") {
  for (const auto& mesh : sample_meshes()) {
    INFO(mesh.origin());
    double boundary_length = 0;
    std::size_t interior_sides = 0;
    for (std::size_t e = 0; e < mesh.triangle_count(); ++e)
      for (int k = 0; k < 3; ++k) {
        const auto& t = mesh.triangle(e);
        const int p = t[(k + 1) % 3], q = t[(k + 2) % 3];
        const int f = mesh.neighbour(e, k);
        INFO("edge opposite vertex " << k << " of triangle " << e);
        if (f < 0) {
          bool on_one_side = false;
          for (int s = 0; s < 4; ++s) on_one_side |= mesh.on_side(p, s) && mesh.on_side(q, s);
          CHECK(on_one_side);
          const Point2 &x = mesh.nodes()[p], &y = mesh.nodes()[q];
          boundary_length += std::hypot(y[0] - x[0], y[1] - x[1]);
          continue;
        }
        ++interior_sides;
        REQUIRE(f != static_cast<int>(e));
        REQUIRE(static_cast<std::size_t>(f) < mesh.triangle_count());
        int back = -1;
        for (int j = 0; j < 3; ++j)
          if (mesh.neighbour(f, j) == static_cast<int>(e)) back = j;
        REQUIRE(back >= 0);
        const auto& u = mesh.triangle(f);
        // the same edge, traversed the other way
        CHECK(u[(back + 1) % 3] == q);
        CHECK(u[(back + 2) % 3] == p);
      }
    CHECK(boundary_length == Approx(2 * (mesh.box()[0] + mesh.box()[1])).epsilon(1e-12));
    // Euler for a disc: edges = nodes + triangles - 1
    const std::size_t boundary_edges = 3 * mesh.triangle_count() - interior_sides;
    CHECK(interior_sides / 2 + boundary_edges == mesh.node_count() + mesh.triangle_count() - 1);
  }
}

TEST_CASE("the colouring puts every triangle in one colour, and no two of a colour share a node", "[mesh]") {
  for (const auto& mesh : sample_meshes()) {
    INFO(mesh.origin());
    REQUIRE(mesh.colours() >= 1);
    CHECK(mesh.colour_start(0) == 0);
    CHECK(mesh.colour_start(mesh.colours()) == static_cast<int>(mesh.triangle_count()));
    const auto& order = mesh.elements_by_colour();
    REQUIRE(order.size() == mesh.triangle_count());
    std::vector<int> seen(mesh.triangle_count(), 0);
    std::size_t max_at_node = 0;
    std::vector<std::size_t> at_node(mesh.node_count(), 0);
    for (std::size_t e = 0; e < mesh.triangle_count(); ++e)
      for (int v : mesh.triangle(e)) max_at_node = std::max(max_at_node, ++at_node[v]);
    for (int c = 0; c < mesh.colours(); ++c) {
      INFO("colour " << c);
      REQUIRE(mesh.colour_start(c) < mesh.colour_start(c + 1));  // no empty colour
      std::vector<int> owner(mesh.node_count(), -1);
      for (int i = mesh.colour_start(c); i < mesh.colour_start(c + 1); ++i) {
        const int e = order[i];
        REQUIRE(e >= 0);
        REQUIRE(static_cast<std::size_t>(e) < mesh.triangle_count());
        ++seen[e];
        for (int v : mesh.triangle(e)) {
          INFO("triangles " << owner[v] << " and " << e << " share node " << v);
          CHECK(owner[v] == -1);
          owner[v] = e;
        }
      }
    }
    CHECK(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }));
    // greedy colouring: at most one colour more than the triangles a triangle can touch through its 3 nodes
    CHECK(mesh.colours() <= static_cast<int>(3 * (max_at_node - 1) + 1));
  }
}

TEST_CASE("on_side flags match the node coordinates", "[mesh]") {
  for (const auto& mesh : sample_meshes()) {
    INFO(mesh.origin());
    const double a = mesh.box()[0], b = mesh.box()[1], tol = 1e-9 * std::max(a, b);
    std::array<int, 4> count{};
    for (std::size_t i = 0; i < mesh.node_count(); ++i) {
      const Point2& x = mesh.nodes()[i];
      const std::array<bool, 4> expected{std::abs(x[0]) <= tol, std::abs(x[0] - a) <= tol, std::abs(x[1]) <= tol,
                                         std::abs(x[1] - b) <= tol};
      for (int s = 0; s < 4; ++s) {
        INFO("node " << i << " side " << s);
        CHECK(mesh.on_side(i, s) == expected[s]);
        count[s] += expected[s];
      }
    }
    for (int s = 0; s < 4; ++s) CHECK(count[s] >= 2);  // every side has at least its two corners
  }
  // the jittered mesh: nx + 1 nodes on the sides y = const, ny + 1 on x = const
  const auto mesh = make_jittered_mesh({2.0, 0.5}, 13, 5, 0.2, 7);
  std::array<int, 4> count{};
  for (std::size_t i = 0; i < mesh.node_count(); ++i)
    for (int s = 0; s < 4; ++s) count[s] += mesh.on_side(i, s);
  CHECK(count == std::array<int, 4>{6, 6, 14, 14});
}

TEST_CASE("make_jittered_mesh is reproducible for a seed and keeps the boundary in place", "[mesh]") {
  const auto a = make_jittered_mesh({2.0, 1.0}, 8, 6, 0.2, 42), b = make_jittered_mesh({2.0, 1.0}, 8, 6, 0.2, 42);
  CHECK(a.nodes() == b.nodes());
  CHECK(a.triangles() == b.triangles());
  const auto c = make_jittered_mesh({2.0, 1.0}, 8, 6, 0.2, 43);
  CHECK(a.nodes() != c.nodes());
  CHECK(a.triangles() == c.triangles());
  CHECK(a.node_count() == 9 * 7);
  CHECK(a.triangle_count() == 2 * 8 * 6);
  const auto regular = make_jittered_mesh({2.0, 1.0}, 8, 6, 0.0, 42);
  std::size_t moved = 0;
  std::array<double, 2> largest{};  // the largest shift in each direction
  for (std::size_t i = 0; i < a.node_count(); ++i) {
    const Point2 &x = a.nodes()[i], &r = regular.nodes()[i];
    CHECK(r[0] == Approx(0.25 * (i % 9)));
    CHECK(r[1] == Approx((1.0 / 6) * (i / 9)));
    // moved by at most the jitter, and not at all across the boundary
    CHECK(std::abs(x[0] - r[0]) <= 0.2 * 0.25 + 1e-15);
    CHECK(std::abs(x[1] - r[1]) <= 0.2 / 6 + 1e-15);
    const bool boundary_x = i % 9 == 0 || i % 9 == 8, boundary_y = i / 9 == 0 || i / 9 == 6;
    if (boundary_x) CHECK(x[0] == r[0]);
    if (boundary_y) CHECK(x[1] == r[1]);
    moved += x != r;
    for (int d = 0; d < 2; ++d) largest[d] = std::max(largest[d], std::abs(x[d] - r[d]));
  }
  CHECK(moved >= 7 * 5);  // every interior node moves
  // 35 uniform shifts: the largest is near the bound, in each direction's own cell size
  CHECK(largest[0] > 0.75 * 0.2 * 0.25);
  CHECK(largest[1] > 0.75 * 0.2 / 6);
}

TEST_CASE("the TriangleMesh constructor refuses bad meshes naming the origin", "[mesh]") {
  const std::vector<Point2> square{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const auto error = [&](std::vector<Point2> nodes, std::vector<std::array<int, 3>> triangles) -> std::string {
    try {
      TriangleMesh(std::move(nodes), std::move(triangles), {1, 1}, "origin.msh");
    } catch (const SceneError& e) {
      return e.what();
    }
    return "(no error)";
  };
  CHECK(error(square, {{0, 1, 2}, {0, 2, 3}}) == "(no error)");
  CHECK_THAT(error(square, {}), StartsWith("origin.msh") && Contains("no triangles"));
  CHECK_THAT(error(square, {{0, 1, 2}, {0, 3, 2}}), StartsWith("origin.msh") && Contains("triangle 1 is inverted"));
  CHECK_THAT(error({{0, 0}, {1, 0}, {0.5, 0}, {1, 1}}, {{0, 1, 3}, {0, 2, 1}}),
             StartsWith("origin.msh") && Contains("triangle 1 is degenerate"));
  CHECK_THAT(error(square, {{0, 1, 2}, {0, 2, 7}}), StartsWith("origin.msh") && Contains("triangle 1 names node 7"));
  CHECK_THAT(error(square, {{0, 1, 2}, {0, 2, -1}}), StartsWith("origin.msh") && Contains("triangle 1"));
  CHECK_THAT(error({{0, 0}, {1, 0}, {1, 1}, {0, 1}, {1.5, 0.5}}, {{0, 1, 2}, {0, 2, 3}, {1, 4, 2}}),
             StartsWith("origin.msh") && Contains("node 4") && Contains("outside"));
  // three triangles on the edge 0-2
  CHECK_THAT(error({{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.9, 0.1}}, {{0, 1, 2}, {0, 2, 3}, {0, 4, 2}}),
             StartsWith("origin.msh") && Contains("triangle 2") && Contains("not manifold"));
}
