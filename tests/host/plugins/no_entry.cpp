// A shared library that is not an auvnav plugin: it exports a function, but
// not the entry point auvnav_plugin_entry_v1.
extern "C" __attribute__((visibility("default"))) int auvnav_test_not_a_plugin()
{
	return 42;
}
