#pragma once
/** @file register.h
 *  Registration of auvnav's observation classes with MRPT's class registry.
 *  Loading libauvnav_obs registers them automatically; calling this is only
 *  needed to force the library to be linked in (it is idempotent). */
namespace auvnav::obs
{
void registerAllClasses();
}
