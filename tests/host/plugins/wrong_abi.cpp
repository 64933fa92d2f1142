// A plugin whose entry point announces ABI version 99 (hand-written entry; the
// AUVNAV_PLUGIN macro always writes the current version).
#include <auvnav/plugin_api.h>

namespace
{
auvnav::MeasurementModel* create(const char*, const char*, char* error, size_t size)
{
	std::snprintf(error, size, "never called");
	return nullptr;
}
void destroy(auvnav::MeasurementModel*) {}
const AuvnavPluginEntry kEntry = {{99u, AUVNAV_PLUGIN_API_VERSION, "wrong_abi", "0.0.1",
                                   AUVNAV_BUILD_FINGERPRINT, "test: wrong ABI version"},
                                  &create,
                                  &destroy};
}  // namespace

extern "C" __attribute__((visibility("default"))) const AuvnavPluginEntry* auvnav_plugin_entry_v1()
{
	return &kEntry;
}
