// Measurement's typed payload (measurement_function.h): what a plugin writes in
// prepare is what h reads, it travels with copies of the Measurement, and it
// lives inside the Measurement (no allocation; checked at compile time).
#include <auvnav/measurement_function.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <iterator>
#include <type_traits>
#include <vector>

namespace
{
struct LeverArm
{
	double x_m, y_m, z_m;
	int beam;
};
struct Largest
{
	double v[auvnav::MeasurementPayload::kCapacity / sizeof(double)];
};
}  // namespace

TEST(MeasurementPayload, WhatIsSetIsReadBack)
{
	auvnav::Measurement m;
	m.setPayload(LeverArm{0.4, -0.1, 0.3, 2});
	const auvnav::Measurement& cm = m;
	EXPECT_EQ(cm.payload<LeverArm>().x_m, 0.4);
	EXPECT_EQ(cm.payload<LeverArm>().y_m, -0.1);
	EXPECT_EQ(cm.payload<LeverArm>().z_m, 0.3);
	EXPECT_EQ(cm.payload<LeverArm>().beam, 2);
	m.payload<LeverArm>().beam = 3;  // written in place
	EXPECT_EQ(cm.payload<LeverArm>().beam, 3);
}

TEST(MeasurementPayload, TravelsWithCopiesAndInVectors)
{
	std::vector<auvnav::Measurement> out;
	for (int i = 0; i < 20; ++i)  // reallocations copy/move the elements
	{
		auvnav::Measurement m;
		m.setPayload(LeverArm{double(i), 0, 0, i});
		out.push_back(m);
	}
	for (int i = 0; i < 20; ++i) EXPECT_EQ(out[i].payload<LeverArm>().beam, i);
	const auvnav::Measurement copy = out[7];
	EXPECT_EQ(copy.payload<LeverArm>().x_m, 7.0);
}

TEST(MeasurementPayload, FixedStorageInsideTheMeasurement)
{
	// The full capacity is usable, aligned for doubles and Eigen's fixed types.
	auvnav::Measurement m;
	Largest big{};
	for (std::size_t i = 0; i < std::size(big.v); ++i) big.v[i] = double(i);
	m.setPayload(big);
	EXPECT_EQ(m.payload<Largest>().v[std::size(big.v) - 1], double(std::size(big.v) - 1));
	EXPECT_EQ(
	    reinterpret_cast<std::uintptr_t>(&m.payload<Largest>()) % auvnav::MeasurementPayload::kAlignment, 0u);
	static_assert(sizeof(auvnav::MeasurementPayload) == auvnav::MeasurementPayload::kCapacity);
	static_assert(std::is_trivially_copyable_v<auvnav::MeasurementPayload>);
	// A default Measurement reads zeros (value-initialised storage).
	const auvnav::Measurement fresh;
	EXPECT_EQ(fresh.payload<LeverArm>().x_m, 0.0);
	EXPECT_EQ(fresh.payload<LeverArm>().beam, 0);
}
