#pragma once
// Small helpers shared by the observation classes' serializers.
//
// Contract: every reader here either returns a value that the class's own
// writer could have produced or throws std::exception whose message starts
// with "corrupt data:" and names the class and the field. Nothing is
// allocated before the size that drives it has been checked, so a damaged
// record costs at most the bounds below, never gigabytes.
#include <auvnav/obs/MountedObservation.h>
#include <mrpt/core/exceptions.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/serialization/CArchive.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

namespace auvnav::obs::detail
{
/** Longest sensor label accepted on reading. Labels are short identifiers;
 *  the bound only stops a damaged length from allocating gigabytes. */
constexpr uint32_t kMaxLabelBytes = 4096;

/** Reads an element count and refuses absurd values, so that a corrupt
 *  file gives a clear error instead of a huge allocation. */
inline uint32_t readCount(mrpt::serialization::CArchive& in, uint32_t max_count, const char* what)
{
	uint32_t n = 0;
	in >> n;
	if (n > max_count)
		THROW_EXCEPTION_FMT("corrupt data: %s count %u exceeds the limit %u", what, static_cast<unsigned>(n),
		                    static_cast<unsigned>(max_count));
	return n;
}

/** A uint8 code that must be below `count` (an enum with `count` values).
 *  Enums are never read directly: a byte no writer produces would become an
 *  enumerator no code handles. */
inline uint8_t readCode(mrpt::serialization::CArchive& in, uint8_t count, const char* cls, const char* field)
{
	uint8_t v = 0;
	in >> v;
	if (v >= count)
		THROW_EXCEPTION_FMT("corrupt data: %s %s code %u out of range 0..%u", cls, field, unsigned(v),
		                    unsigned(count - 1));
	return v;
}

/** A flag written as one byte 0 or 1. MRPT reads a bool by copying the byte
 *  into it, so any other value would be undefined behaviour: read the byte
 *  and refuse what no writer produces. */
inline bool readFlag(mrpt::serialization::CArchive& in, const char* cls, const char* field)
{
	uint8_t v = 0;
	in >> v;
	if (v > 1)
		THROW_EXCEPTION_FMT("corrupt data: %s %s flag byte %u is neither 0 nor 1", cls, field, unsigned(v));
	return v != 0;
}

/** Writes a flag as readFlag() reads it (the same byte MRPT writes for a bool). */
inline void writeFlag(mrpt::serialization::CArchive& out, bool b)
{
	out << static_cast<uint8_t>(b ? 1 : 0);
}

/** Reads a std::string in MRPT's layout (uint32 length, then the bytes), as
 *  `in >> s` would, but refuses a length above `max_bytes` before allocating
 *  (MRPT's own reader resizes to whatever length the file claims). */
inline std::string readString(mrpt::serialization::CArchive& in, uint32_t max_bytes, const char* cls,
                              const char* field)
{
	uint32_t n = 0;
	in >> n;
	if (n > max_bytes)
		THROW_EXCEPTION_FMT("corrupt data: %s %s length %u exceeds the limit %u", cls, field,
		                    static_cast<unsigned>(n), static_cast<unsigned>(max_bytes));
	std::string s(n, '\0');
	if (n) in.ReadBuffer(s.data(), n);
	return s;
}

/** The sensor label, bounded by kMaxLabelBytes. */
inline std::string readLabel(mrpt::serialization::CArchive& in, const char* cls)
{
	return readString(in, kMaxLabelBytes, cls, "sensorLabel");
}

/** Reads a CPose3D and refuses one that no CPose3D could hold: a translation
 *  that is not finite or a rotation that is not a proper rotation matrix
 *  (a damaged mounting pose would otherwise reach every measurement model). */
inline void readPose(mrpt::serialization::CArchive& in, mrpt::poses::CPose3D& pose, const char* cls)
{
	in >> pose;
	const auto& R = pose.getRotationMatrix();
	bool ok = std::isfinite(pose.x()) && std::isfinite(pose.y()) && std::isfinite(pose.z());
	for (int r = 0; ok && r < 3; ++r)
		for (int c = 0; ok && c < 3; ++c)
		{
			double dot = 0;  // column r . column c: 1 on the diagonal, 0 off it
			for (int k = 0; k < 3; ++k) dot += R(k, r) * R(k, c);
			ok = std::isfinite(dot) && std::abs(dot - (r == c ? 1.0 : 0.0)) < 1e-6;
		}
	if (ok) ok = R.det() > 0;  // a reflection is no rotation
	if (!ok) THROW_EXCEPTION_FMT("corrupt data: %s sensorPose is not a finite rigid transform", cls);
}

/** Every auvnav record starts with the timestamp and the sensor label, in
 *  MRPT's layouts; readHead() reads what writeHead() writes, the label
 *  bounded by kMaxLabelBytes. */
inline void writeHead(mrpt::serialization::CArchive& out, const mrpt::obs::CObservation& o)
{
	out << o.timestamp << o.sensorLabel;
}

inline void readHead(mrpt::serialization::CArchive& in, mrpt::obs::CObservation& o, const char* cls)
{
	in >> o.timestamp;
	o.sensorLabel = readLabel(in, cls);
}

/** A mounted sensor's record continues with its pose: the head above, then
 *  `sensorPose` (read through readPose(), so refused unless rigid). */
inline void writeMountedHead(mrpt::serialization::CArchive& out, const MountedObservation& o)
{
	writeHead(out, o);
	out << o.sensorPose;
}

inline void readMountedHead(mrpt::serialization::CArchive& in, MountedObservation& o, const char* cls)
{
	readHead(in, o, cls);
	readPose(in, o.sensorPose, cls);
}
/** Reads a record into a fresh object and adopts it only once `read(fresh)`
 *  has returned: a record refused half-way (any exception) leaves `self` as
 *  it was. Callers check the version before, so that the exception for an
 *  unknown one names their serializeFrom(). */
template <class Obs, class ReadFn>
void readWhole(Obs& self, ReadFn&& read)
{
	Obs fresh;
	read(fresh);
	self = std::move(fresh);
}
}  // namespace auvnav::obs::detail
