// Linked into every harness: runtime settings that keep the fuzzers on the
// project's own code.

// glibc's backtrace() replaced by one that records nothing. MRPT captures a
// call stack in each exception it throws and formats it (dladdr, demangling)
// whenever what() is called, which its own readers do when they wrap an
// error: slow, above all under ASan, and nearly every fuzz input is refused,
// so the fuzzers spent their time formatting call stacks. The executable's
// definition takes precedence over libc's for MRPT's libraries too; the
// sanitizers and libFuzzer unwind with their own code.
extern "C" int backtrace(void** buffer, int size)
{
	(void)buffer;
	(void)size;
	return 0;
}

// LeakSanitizer: leaks of MRPT and libfyaml, not ours, that cannot be fixed
// here: libfyaml's input (fy_input_alloc, through MRPT's YAML reader), and
// the message CObservationGPS's reader creates (gnss_message::Factory) and
// drops when the message's data is damaged (regressions/*/leak-mrpt-gnss-*).
extern "C" const char* __lsan_default_suppressions()
{
	return "leak:libfyaml.so\n"
	       "leak:gnss_message::Factory\n";
}
