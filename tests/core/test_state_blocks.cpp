// The state block table (state.h) and the enum name tables (enum_names.h).
#include <auvnav/enum_names.h>
#include <auvnav/state.h>
#include <gtest/gtest.h>

#include <string>

using namespace auvnav;

TEST(StateBlocks, TileTheCoreStateInOrderWithOneBitEach)
{
	int next = 0;
	uint32_t bit = 1;
	for (const StateBlockInfo& b : coreStateBlocks())
	{
		SCOPED_TRACE(b.name);
		EXPECT_EQ(b.bit, bit);
		EXPECT_EQ(b.begin, next);
		EXPECT_GT(b.size, 0);
		for (int i = b.begin; i < b.begin + b.size; ++i)
		{
			EXPECT_EQ(blockOfCoordinate(i), b.bit);
			// Every coordinate's name starts with its block's prefix.
			EXPECT_EQ(tangentNames()[static_cast<std::size_t>(i)].rfind(b.prefix, 0), 0u)
			    << tangentNames()[static_cast<std::size_t>(i)];
		}
		EXPECT_EQ(tangentPrefix(b.bit), b.begin + b.size);
		next = b.begin + b.size;
		bit <<= 1;
	}
	EXPECT_EQ(next, idx::core_dim);
	EXPECT_EQ(bit, static_cast<uint32_t>(kPluginStates));
}

namespace
{
enum class Colour
{
	Red,
	Green,
	Blue
};
constexpr const char* kColourNames[] = {"red", "green", "blue"};
static_assert(namesEveryValue(kColourNames, Colour::Blue));
}  // namespace

TEST(EnumNames, NameAndParseBackEveryValue)
{
	for (Colour c : {Colour::Red, Colour::Green, Colour::Blue})
	{
		Colour back = Colour::Red;
		ASSERT_TRUE(parseName(kColourNames, nameOf(kColourNames, c, "?"), back));
		EXPECT_EQ(back, c);
	}
	EXPECT_STREQ(nameOf(kColourNames, Colour::Green, "?"), "green");
	EXPECT_STREQ(nameOf(kColourNames, static_cast<Colour>(7), "?"), "?");
}

TEST(EnumNames, AnUnknownNameLeavesTheValueAlone)
{
	Colour c = Colour::Blue;
	EXPECT_FALSE(parseName(kColourNames, "Green", c));  // exact, case included
	EXPECT_FALSE(parseName(kColourNames, "", c));
	EXPECT_EQ(c, Colour::Blue);
}
