#pragma once
// The rim of a scanned sheet, and the part's side below it (issue 45). A scan shows the faces a sensor
// saw; where the sheet of points ends, the part does not end in air: its side goes on, unseen, down to
// the table. A tool planned on the points alone passes under such an edge (from a tilted direction it
// sees nothing there) and cuts the side below it. So the rim is found, and the side is put back as
// points a tool must not enter.
//
// The rim. The cloud is thinned to one centroid per cubic cell; a centroid is on the rim when its
// neighbours (within 2.5 cells), seen in their least-squares plane, leave an angular gap wider than
// `gap` degrees around it: an inner point is surrounded, a border point has a half-plane free (180°),
// a corner more; or when, the neighbourhood not being a plane (a sharp crest's end at the rim), the
// neighbours' centroid stands off to one side in their plane by more than 30 % of the radius, or the
// cell has at most 65 % of a typical cell's neighbours and their centroid stands off by 20 %; and in
// every case when the scan's own points agree: a disc of the neighbourhood's radius just beyond the
// cell (along its outward direction or up to 60° off it) holds under a quarter of the points about
// it (the cells read a curved scan at random unevenly, and a cell amid it may look like an edge). Each
// rim cell then gives its outermost scanned point (the farthest along the gap's
// bisector), so the side stands under the scanned edge itself, not half a cell inside it. A cloud
// that closes on itself (a ball on a neck down to the table) has its rim on the table only. Rim
// points up to two neighbour radii apart are linked too when the edge runs between them (outward
// directions within 60°, the line between them within 60° of square to both): on a scan at random a
// cell at the edge may not read as a rim cell, and a break in the chain left the side with a gap.
//
// The side. The scan's last points are not the part's edge: the edge lies somewhere in the next gap
// (a scanner's grid ends within a spacing of it; points at random, within 2.5 spacings in all but
// 5e-5 of places, and the rim's outward direction is itself a little off). So the side stands three
// spacings beyond the rim, in the sheet's plane (3 spacings / sin(gap / 2) at a corner, at most 4.5),
// where its top continues the sheet, flat: on the scanned sheet the tool stays as low as before (no
// stock), and it does not roll over the scanned edge and round off the part's true edge beyond it.
// Vertical lines (the part frame's -Z, the table's normal) from there, and from points every `spacing`
// along the rim between neighbouring rim points (as high as the higher where the line between them
// rises more than it runs and more than twice what the higher one's faces rise along it: the corner at
// a step's end, not a steep flank's straight edge), go down to the base's top, every `spacing` mm: a
// wall of points dense enough that a ball of radius r dips between them by at most
// r - sqrt(r^2 - spacing^2 / 2). The strip between the rim and the side is filled the same way.
#include "geometry/cloud_cells.hpp"

#include <Eigen/Core>

#include <span>
#include <utility>
#include <vector>

namespace drom::geometry {

struct CloudRim {
  std::vector<Eigen::Vector3d> points;   // the outermost scanned point of each rim cell
  std::vector<Eigen::Vector3d> outward;  // unit, in the sheet's plane there, off the sheet
  std::vector<double> gap;               // the free angle around each (rad): pi on a straight edge, more at a corner
  std::vector<Eigen::Vector3d> edge;     // where the side stands: the sheet continued from each rim point
  std::vector<std::vector<Eigen::Vector3d>> strip;  // per rim point: the sheet continued out to its edge, every spacing
  // Per rim point: the normals (z >= 0) of the faces its cell's surface shows, one on a smooth face, two
  // at a crease, none where no surface was fitted.
  std::vector<std::vector<Eigen::Vector3d>> faces;
  std::vector<std::pair<int, int>> links;  // neighbouring rim points (i < j)
  double cell = 0;                       // the thinning cell, mm
  double spacing = 0;                    // the scan's typical spacing the cell came from, mm
};

// `noise`: the scan's (geometry/cloud_noise.hpp); `step`: between the strip's points (mm). The sheet is
// continued on the surface its points describe around the rim cell (geometry/cloud_cells.hpp's
// LocalSurface: a quadric, or two planes at a crease), put three times its fit's uncertainty above
// and below. `cell` <= 0: 1.5 times the scan's typical spacing (from the 8th-neighbour distances of up
// to 4 000 points), at least 0.2 mm.
// `margin`: added to that uncertainty (the strip's points are put that much farther above and below:
// what the sheet may curve between the rim points the strip is drawn from).
CloudRim find_rim(std::span<const Eigen::Vector3d> points, double noise, double step, double margin = 0, double cell = 0, double gap_degrees = 120);
// On the cells of a survey already made (geometry/cloud_cells.hpp).
CloudRim find_rim(std::span<const Eigen::Vector3d> points, const ScanSurvey& survey, double noise, double step, double margin = 0, double gap_degrees = 120);

// The side below the rim down to z = base_top (nothing where the rim is at or below it), and the
// strips out to it; with `depth` > 0, down to `depth` below each point of the rim only (and never
// below base_top).
std::vector<Eigen::Vector3d> side_points(const CloudRim& rim, double base_top, double spacing, double depth = 0);

}  // namespace drom::geometry
