// A plugin with the right ABI version but built "with another toolchain": its
// build fingerprint differs from the host's.
#include <auvnav/plugin_api.h>

namespace
{
auvnav::MeasurementModel* create(const char*, const char*, char* error, size_t size)
{
	std::snprintf(error, size, "never called");
	return nullptr;
}
void destroy(auvnav::MeasurementModel*) {}
const AuvnavPluginEntry kEntry = {
    {AUVNAV_PLUGIN_ABI_VERSION, AUVNAV_PLUGIN_API_VERSION, "wrong_fingerprint", "0.0.1",
     "gcc-0.0 eigen-3.0.0 align-8 mrpt-0x100 state-42", "test: foreign build"},
    &create,
    &destroy};
}  // namespace

extern "C" __attribute__((visibility("default"))) const AuvnavPluginEntry* auvnav_plugin_entry_v1()
{
	return &kEntry;
}
