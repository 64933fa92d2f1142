#pragma once
/** @file register.h
 *  Registration of auvnav's observation classes with MRPT's class registry.
 *  Nothing to call: every target that links auvnav::obs compiles a small
 *  source that calls this before main (link_registration.cpp), which also
 *  keeps the library in a link made with --as-needed. Idempotent. */
namespace auvnav::obs
{
void registerAllClasses();
}
