#pragma once
// What `drom finish` writes for people and machines: the zone map (VTK), the passes as contact and
// tool-tip polylines (VTK), the CL data (CSV), the 3-axis program (G-code), and the time and length
// breakdown per zone (CSV). docs/outputs.md describes each file.
#include "paths/finish/clustering.hpp"
#include "paths/finish/finishing_plan.hpp"
#include "paths/finish/surface_samples.hpp"
#include "machine/cl_data.hpp"

#include <filesystem>
#include <string>

namespace drom::paths {

// The sample grid as quads with each cell's zone, cluster, slope and steepest azimuth (degrees).
void write_zone_map(const std::filesystem::path& path, const geometry::NurbsSurface& surface, const SurfaceSamples& samples, const Zones& zones);
// Every pass's contact polyline and tool-tip polyline (part frame), with zone, pass, kind and spacing.
void write_pass_polylines(const std::filesystem::path& path, const FinishingPlan& plan, const Tool& tool);
// zone, pass, point, tool tip (part frame), tool axis, contact point, tool tip in the zone's machine frame.
void write_cl_csv(const std::filesystem::path& path, const FinishingPlan& plan, const Tool& tool);
// The plan as cutter-location data for machine/ (tool tips and axes in the part frame): each zone
// entered from `clearance` above its first tip along its tool axis by rapids, the last `approach` mm
// plunged at half the feed, its passes and links at the feed, its retracts by rapids.
machine::ClProgram cl_program(const FinishingPlan& plan, const Tool& tool, double feed_mm_per_min, double clearance, double approach);
// Per zone: setup, passes, times and lengths; then the moves between zones and the totals.
void write_breakdown_csv(const std::filesystem::path& path, const FinishingPlan& plan);

}  // namespace drom::paths
