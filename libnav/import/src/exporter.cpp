// exportRawlog (exporter.h): a rawlog read twice, array sizes per label and
// then the rows, into one CSV file per label and the import spec.
#include <auvnav/import/exporter.h>
#include <auvnav/import/record.h>
#include <auvnav/import/time_format.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/obs/CObservationThrusters.h>
#include <auvnav/obs/CObservationUSBL.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/system/filesystem.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>

#include "export_csv.h"
#include "export_spec.h"

namespace auvnav::import
{
namespace
{
using detail::adcpRow;
using detail::classOf;
using detail::csvQuoted;
using detail::dvlRow;
using detail::exact;
using detail::fileSafe;
using detail::gpsRow;
using detail::header;
using detail::imuFieldsWithoutColumn;
using detail::imuRow;
using detail::poseCells;
using detail::specText;
using detail::thrusterRow;
using detail::thrusterUnit;
using detail::usblRow;

/** One label's CSV file and what its layout needs to know from pass 1. */
struct LabelOut
{
	std::string cls, file_name, stem;  // stem: file name without .csv (unique per label)
	std::size_t max_array = 0;         // beams, cells or thrusters
	std::string thruster_unit;         // of the label's first row: the spec has one unit per label
	std::unique_ptr<std::ofstream> out;
	std::size_t rows = 0;
};
}  // namespace

void exportRawlog(const std::string& rawlog, const std::string& out_dir, ExportReport& report)
{
	report = ExportReport{};
	std::map<std::string, LabelOut> labels;
	std::vector<std::string> order;
	// Pass 1: classes and array sizes per label.
	{
		io::RawlogReader in(rawlog);
		while (auto o = in.next())
		{
			const std::string cls = classOf(*o);
			if (!fromMrptTimeChecked(o->timestamp))
			{
				report.skipped_by_reason
				    ["observation without a valid timestamp (invalid, or outside 1678..2262) (" +
				     o->sensorLabel + ")"]++;
				continue;
			}
			if (cls.empty())
			{
				report.skipped_by_reason[std::string("class ") + o->GetRuntimeClass()->className +
				                         " not exported"]++;
				continue;
			}
			auto it = labels.find(o->sensorLabel);
			if (it == labels.end())
			{
				it = labels.emplace(o->sensorLabel, LabelOut{}).first;
				it->second.cls = cls;
				order.push_back(o->sensorLabel);
			}
			LabelOut& l = it->second;
			if (l.cls != cls)
			{
				report.skipped_by_reason["label " + o->sensorLabel + " also used by class " + cls +
				                         ": not exported"]++;
				continue;
			}
			if (const auto* d = dynamic_cast<const auvnav::obs::CObservationDVL*>(o.get()))
				l.max_array = std::max(l.max_array, d->beams.size());
			if (const auto* a = dynamic_cast<const auvnav::obs::CObservationADCP*>(o.get()))
				l.max_array = std::max(l.max_array, a->cells.size());
			if (const auto* t = dynamic_cast<const auvnav::obs::CObservationThrusters*>(o.get()))
			{
				l.max_array = std::max(l.max_array, t->effort.size());
				if (l.thruster_unit.empty()) l.thruster_unit = thrusterUnit(*t);
			}
		}
	}
	// With its parents, as every other program's --out.
	std::error_code ec;
	std::filesystem::create_directories(out_dir, ec);
	if (ec || !std::filesystem::is_directory(out_dir))
		throw ImportError(out_dir + ": cannot create the output folder" +
		                  (ec ? ": " + ec.message() : std::string()));
	std::map<std::string, std::string> units, files;
	std::vector<std::pair<std::string, std::string>> spec_labels;
	std::set<std::string>
	    stems_used;  // lower case: "A B" and "A_B" (or "a_b" on a case-blind disk) share no file
	for (const auto& label : order)
	{
		LabelOut& l = labels[label];
		std::string stem = fileSafe(label);
		auto lower = [](std::string x)
		{
			for (char& c : x) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
			return x;
		};
		for (int k = 2; stems_used.count(lower(stem)); ++k) stem = fileSafe(label) + "_" + std::to_string(k);
		stems_used.insert(lower(stem));
		l.stem = stem;
		l.file_name = stem + ".csv";
		const std::string path = out_dir + "/" + l.file_name;
		l.out = std::make_unique<std::ofstream>(path);
		if (!*l.out) throw ImportError(path + ": cannot write");
		*l.out << header(l.cls, l.max_array) << "\n";
		if (l.cls == "image" && !mrpt::system::directoryExists(out_dir + "/" + stem))
			mrpt::system::createDirectory(out_dir + "/" + stem);
		spec_labels.emplace_back(label, l.cls);
		files[label] = l.file_name;
		if (l.cls == "thrusters") units[label] = l.thruster_unit.empty() ? "N" : l.thruster_unit;
	}
	// Pass 2: the rows.
	io::RawlogReader in(rawlog);
	while (auto o = in.next())
	{
		auto it = labels.find(o->sensorLabel);
		const auto t_ns = fromMrptTimeChecked(o->timestamp);
		if (it == labels.end() || classOf(*o) != it->second.cls || !t_ns) continue;
		LabelOut& l = it->second;
		// What the layout has no column for is counted (exporter.h's contract).
		const auto* th = dynamic_cast<const auvnav::obs::CObservationThrusters*>(o.get());
		if (th && thrusterUnit(*th) != l.thruster_unit)
		{
			// import.yaml has one unit per label: rows in another unit would come back relabelled.
			report
			    .skipped_by_reason["thrusters " + o->sensorLabel + ": rows in " + thrusterUnit(*th) +
			                       " (the label's first rows are in " + l.thruster_unit + ") not exported"]++;
			continue;
		}
		std::string row = formatSeconds7(*t_ns) + ",";
		if (const auto* imu = dynamic_cast<const mrpt::obs::CObservationIMU*>(o.get()))
		{
			row += imuRow(*imu);
			for (const auto& f : imuFieldsWithoutColumn(*imu))
				report
				    .skipped_by_reason["imu " + o->sensorLabel + ": " + f + " has no column, not exported"]++;
		}
		else if (const auto* g = dynamic_cast<const mrpt::obs::CObservationGPS*>(o.get()))
		{
			row += gpsRow(*g);
			for (const auto& [type, msg] : g->messages)
				if (type != mrpt::obs::gnss::NMEA_GGA && msg.get())
					report.skipped_by_reason["gps " + o->sensorLabel + ": message " +
					                         msg->getMessageTypeAsString() + " not exported (only GGA)"]++;
		}
		else if (const auto* p = dynamic_cast<const auvnav::obs::CObservationPressure*>(o.get()))
			row += exact(p->pressure_pa) + "," + exact(p->temperature_c) + "," + poseCells(p->sensorPose);
		else if (const auto* u = dynamic_cast<const auvnav::obs::CObservationUSBL*>(o.get()))
			row += usblRow(*u);
		else if (const auto* d = dynamic_cast<const auvnav::obs::CObservationDVL*>(o.get()))
			row += dvlRow(*d, l.max_array);
		else if (const auto* a = dynamic_cast<const auvnav::obs::CObservationADCP*>(o.get()))
			row += adcpRow(*a, l.max_array);
		else if (const auto* t = dynamic_cast<const auvnav::obs::CObservationThrusters*>(o.get()))
			row += thrusterRow(*t, l.max_array);
		else if (const auto* im = dynamic_cast<const mrpt::obs::CObservationImage*>(o.get()))
		{
			char name[32];
			std::snprintf(name, sizeof name, "%06zu.png", l.rows);
			const std::string rel = l.stem + "/" + name;
			if (!im->image.saveToFile(out_dir + "/" + rel))
				throw ImportError(out_dir + "/" + rel + ": cannot write the image");
			const auto& c = im->cameraParams;
			row += csvQuoted(rel) + "," + std::to_string(c.ncols) + "," + std::to_string(c.nrows) + "," +
			       exact(c.fx()) + "," + exact(c.fy()) + "," + exact(c.cx()) + "," + exact(c.cy()) + "," +
			       csvQuoted(c.cameraName) + "," + poseCells(im->cameraPose);
			if (std::any_of(c.dist.begin(), c.dist.end(), [](double k) { return k != 0; }))
				report.skipped_by_reason["image " + o->sensorLabel +
				                         ": camera distortion (dist) has no column, not exported"]++;
		}
		*l.out << row << "\n";
		l.rows++;
	}
	for (const auto& label : order)
	{
		LabelOut& l = labels[label];
		l.out->flush();
		if (!*l.out) throw ImportError(out_dir + "/" + l.file_name + ": write failed (disk full?)");
		report.sensors.push_back({label, l.cls, l.file_name, l.rows});
	}
	report.spec_file = out_dir + "/import.yaml";
	std::ofstream spec(report.spec_file);
	spec << specText(spec_labels, files, units, false);
	if (!spec) throw ImportError(report.spec_file + ": cannot write");
}

}  // namespace auvnav::import
