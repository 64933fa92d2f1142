#pragma once
// Internal to the exporter: the CSV layout of each observation class (header
// row, a row per observation, cell texts), as documented in docs/import.md.
#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationThrusters.h>
#include <auvnav/obs/CObservationUSBL.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/poses/CPose3D.h>

#include <cstddef>
#include <string>
#include <vector>

namespace auvnav::import::detail
{
/** Shortest text that reads back as the same double ("nan" for NaN). */
std::string exact(double v);
/** `label` as a file name: other characters than letters, digits, `_`, `-`
 *  and `.` become `_` ("unnamed" if empty). */
std::string fileSafe(const std::string& label);
/** The class name (as in `class:`) `o` is exported as, or empty: not exported. */
std::string classOf(const mrpt::obs::CObservation& o);
/** "rpm" or "N". */
std::string thrusterUnit(const auvnav::obs::CObservationThrusters& t);
/** The pose cells: x, y, z, qw, qx, qy, qz. */
std::string poseCells(const mrpt::poses::CPose3D& p);

/** The header row of class `cls`, with `n` beams, cells or thrusters. */
std::string header(const std::string& cls, std::size_t n);

/** A row's cells after the time, per class; `n` as in header(). */
std::string imuRow(const mrpt::obs::CObservationIMU& o);
/** Geodetic fixes fill latitude/longitude/depth, local ones north/east/down;
 *  the other three cells stay empty (the importer picks the filled set). */
std::string usblRow(const auvnav::obs::CObservationUSBL& o);
std::string gpsRow(const mrpt::obs::CObservationGPS& o);
std::string dvlRow(const auvnav::obs::CObservationDVL& o, std::size_t n);
std::string adcpRow(const auvnav::obs::CObservationADCP& o, std::size_t n);
std::string thrusterRow(const auvnav::obs::CObservationThrusters& o, std::size_t n);

/** `s` as a CSV cell: double-quoted if it holds a comma, a quote or a newline. */
std::string csvQuoted(const std::string& s);

/** The IMU data MRPT can hold that the CSV layout has no column for. */
std::vector<std::string> imuFieldsWithoutColumn(const mrpt::obs::CObservationIMU& o);

}  // namespace auvnav::import::detail
