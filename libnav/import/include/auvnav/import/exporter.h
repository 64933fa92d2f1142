#pragma once
/** @file exporter.h
 *  A rawlog to one CSV file per sensor label (`auvnav-export`), in the layout
 *  documented in docs/import.md, plus `import.yaml`: the import spec that reads
 *  those files back (export → edit in a spreadsheet or Python → import).
 *
 *  Contract: every observation of a class the importer knows (IMU, GPS with a
 *  GGA message, DVL, ADCP, pressure, thrusters, images) becomes one row of
 *  `<label>.csv` (header row first; images as PNG files under `<label>/`).
 *  Numbers are written with 17 significant digits and times as UNIX seconds
 *  with 7 decimals (MRPT's 100 ns), so that the round trip gives back the
 *  same doubles and stamps. Observations of other classes, and data the
 *  layout has no column for, are counted in the report, not dropped silently.
 *  The rawlog is read twice (first the array sizes per label, then the rows).
 */
#include <map>
#include <string>
#include <vector>

namespace auvnav::import
{
struct ExportReport
{
	struct Sensor
	{
		std::string label, observation_class, file;
		std::size_t rows = 0;
	};
	std::vector<Sensor> sensors;
	std::map<std::string, std::size_t> skipped_by_reason;  //!< "class X not exported" → count
	std::string spec_file;
};

/** Exports `rawlog` into folder `out_dir` (created). Throws RawlogError or
 *  ImportError naming the file on unreadable input or unwritable output. */
void exportRawlog(const std::string& rawlog, const std::string& out_dir, ExportReport& report);

/** The import spec text `exportRawlog` writes for the labels and classes of
 *  an export (`label` → class name as in `class:`), with the thruster unit.
 *  `optional_sensors`: every sensor `optional: true` (a spec for exports that
 *  may lack some of the labels, as config/import/auvnav_export.yaml). */
std::string exportSpecText(const std::vector<std::pair<std::string, std::string>>& labels_and_classes,
                           const std::map<std::string, std::string>& thruster_units = {},
                           bool optional_sensors = false);

/** The simulator's labels and classes, in the order of config/import/auvnav_export.yaml. */
std::vector<std::pair<std::string, std::string>> simulatorLabels();

}  // namespace auvnav::import
