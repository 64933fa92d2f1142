// libFuzzer harness: deserialisation of one auvnav observation class
// (AUVNAV_FUZZ_CLASS, set per harness by CMakeLists.txt).
//
// Input: byte 0 is the serialisation version, the rest the class's data, so
// that mutations reach the class's reader rather than MRPT's object header.
// A record the class accepts must describe itself, export a text row, and
// survive write -> read -> write unchanged (what is read is what is written).
#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/obs/CObservationThrusters.h>
#include <auvnav/obs/CObservationUSBL.h>

#include <sstream>

#include "fuzz_support.h"

using namespace auvnav::fuzz;
using Class = auvnav::obs::AUVNAV_FUZZ_CLASS;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size)
{
	if (size < 1) return 0;
	static const std::string name = CLASS_ID(Class)->className;
	Bytes record = objectHeader(name, data[0]);
	record.insert(record.end(), data + 1, data + size);
	record.push_back(0x88);  // MRPT's end flag, so that a complete body is accepted
	mrpt::serialization::CSerializable::Ptr obj;
	try
	{
		obj = readObject(record.data(), record.size());
	}
	catch (const std::exception&)
	{
		return 0;  // refused: the expected outcome for most inputs
	}
	auto o = std::dynamic_pointer_cast<Class>(obj);
	FUZZ_CHECK(o, "ReadObject returned another class");
	std::ostringstream text;
	o->getDescriptionAsText(text);
	(void)o->exportTxtDataRow();
	// Whatever was accepted is written back and reads back to the same bytes.
	const Bytes once = writeObject(*o);
	auto again = std::dynamic_pointer_cast<Class>(readObject(once.data(), once.size()));
	FUZZ_CHECK(again, "a written record was not read back");
	FUZZ_CHECK(writeObject(*again) == once, "write -> read -> write changed the record");
	return 0;
}
