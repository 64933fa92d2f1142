// A program that links auvnav::obs but names none of its classes, linked with
// --as-needed: it still reads auvnav's observations from a rawlog (the
// registration source every consumer compiles, link_registration.cpp).
#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/serialization/CArchive.h>

#include <set>
#include <string>

TEST(ObsAsNeeded, ReadsAuvnavClassesWithoutNamingThem)
{
	mrpt::io::CFileGZInputStream in(AUVNAV_SAMPLE_RAWLOG);
	auto ar = mrpt::serialization::archiveFrom(in);
	std::set<std::string> classes;
	for (int i = 0; i < 2000; ++i)
	{
		const auto obj = ar.ReadObject();
		ASSERT_TRUE(obj);
		classes.insert(obj->GetRuntimeClass()->className);
	}
	EXPECT_TRUE(classes.count("auvnav::obs::CObservationDVL")) << classes.size() << " classes";
	EXPECT_TRUE(classes.count("auvnav::obs::CObservationPressure"));
}
