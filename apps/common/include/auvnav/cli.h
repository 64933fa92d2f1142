#pragma once
/** @file cli.h
 *  Command-line parsing with uniform exit codes for the auvnav programs
 *  (header-only; needs MRPT's TCLAP, CMake target auvnav_tclap).
 *
 *  Exit codes of every program (README, "Exit codes"; ExitCode below): 0 ok,
 *  1 bad command line (unknown option, missing or unreadable argument), 2 bad
 *  input (configuration, unreadable / corrupt / empty rawlog, a log without
 *  what the program needs, a clock jump; the message names it), 3 no result
 *  from valid input (auvnav-run: never initialised; auvnav-calibrate-mag: fit
 *  refused), 4 diverged (auvnav-run), 128 + N stopped by signal N (SIGINT
 *  130, SIGTERM 143; auvnav-run, which ends its outputs first).
 *
 *  Why: MRPT's TCLAP returns false from CmdLine::parse() both after --help /
 *  --version and after a parse error (and prints the whole usage for the
 *  latter); the programs returned 0 for both. parse() below tells them apart
 *  and reports an error as one line on stderr.
 *
 *  ObsLibOption: the `--obs-lib LIB` option (repeatable) of every program
 *  that reads rawlogs; see obs_libraries.h.
 */
#include <auvnav/error_text.h>
#include <auvnav/obs_libraries.h>
#include <auvnav/plugin_host.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace auvnav::cli
{
/** The one definition of the programs' exit codes (file comment). Plain
 *  ints so that `return kExitBadInput;` works from main(). */
enum ExitCode : int
{
	kExitOk = 0,
	kExitUsage = 1,           //!< bad command line
	kExitBadInput = 2,        //!< configuration or input unusable (named on stderr)
	kExitNoResult = 3,        //!< valid input, no result: never initialised, fit refused
	kExitNotInitialized = 3,  //!< auvnav-run's name for kExitNoResult
	kExitDiverged = 4,        //!< auvnav-run: the divergence monitor says diverged
	kExitSignalBase = 128,    //!< + the signal number that stopped the run
};

/** Prints "PROGRAM: error: REASON" on stderr, REASON being the first
 *  meaningful line of `what` (error_text.h: no MRPT exception report).
 *  Returns `code` so that main() can `return cli::fail(...)`. */
inline int fail(const std::string& program, const std::string& what, int code = kExitBadInput)
{
	std::cerr << program << ": error: " << oneLineReason(what) << "\n";
	return code;
}

namespace detail
{
/** TCLAP's output with a one-line failure: "PROGRAM: error: REASON (see PROGRAM --help)". */
class OneLineFailure : public TCLAP::StdOutput
{
 public:
	explicit OneLineFailure(std::string program) : program_(std::move(program)) {}
	void failure(TCLAP::CmdLineInterface& cmd, TCLAP::ArgException& e) override
	{
		failed = true;
		std::string reason = e.error();
		// TCLAP does not say which required argument is missing: name them.
		std::string missing;
		for (const TCLAP::Arg* a : cmd.getArgList())
			if (a->isRequired() && !a->isSet())
				missing += (missing.empty() ? "" : ", ") + (a->longID().rfind('<', 0) == 0
				                                                ? a->longID()
				                                                : "--" + a->getName());  // <RAWLOG> or --name
		if (reason.find("required arguments missing") != std::string::npos && !missing.empty())
			reason = "missing required argument(s): " + missing;
		std::string id = e.argId();
		if (id.rfind("Argument: ", 0) == 0) id = id.substr(10);
		if (!id.empty() && id != " ") reason += ": " + id;
		std::cerr << program_ << ": error: " << reason << " (see " << program_ << " --help)\n";
	}
	bool failed = false;

 private:
	std::string program_;
};
}  // namespace detail

/** Parses the command line. Returns no value when the program should go on;
 *  otherwise the exit code: kExitOk after --help / --version, kExitUsage
 *  after a parse error (reported on stderr). */
inline std::optional<int> parse(TCLAP::CmdLine& cmd, int argc, char** argv, const std::string& program)
{
	// Once an output is set TCLAP deletes none: both live until exit.
	static std::vector<std::unique_ptr<TCLAP::CmdLineOutput>> outputs;
	outputs.emplace_back(cmd.getOutput());
	auto* output = new detail::OneLineFailure(program);
	outputs.emplace_back(output);
	cmd.setOutput(output);
	try
	{
		if (cmd.parse(argc, argv)) return std::nullopt;
	}
	catch (const TCLAP::ArgException& e)  // a specification error (a programming error)
	{
		std::cerr << program << ": error: " << e.error() << "\n";
		return kExitUsage;
	}
	return output->failed ? kExitUsage : kExitOk;
}

/** `--obs-lib LIB` (repeatable): observation libraries to load before a
 *  rawlog is read (obs_libraries.h). Construct it with the other arguments,
 *  call load() after parse() and before opening the rawlog. */
class ObsLibOption
{
 public:
	explicit ObsLibOption(TCLAP::CmdLine& cmd)
	    : arg_("", "obs-lib",
	           "Load an observation-class library (MRPT CObservation subclasses a plugin defines) before "
	           "reading "
	           "the rawlog: a path, or a file name searched in the plugin path and by the dynamic loader "
	           "(repeatable)",
	           false, "LIB", cmd)
	{
	}
	/** Loads the given libraries plus `declared` (e.g. a navigator config's
	 *  declaredObservationLibraries()), searching `search_dirs` (default: the
	 *  plugin host's). Returns kExitBadInput after printing
	 *  "PROGRAM: error: cannot load observation library 'LIB' ..." if one fails. */
	std::optional<int> load(const std::string& program, const std::vector<std::string>& declared = {},
	                        std::optional<std::vector<std::string>> search_dirs = std::nullopt) const
	{
		try
		{
			const std::vector<std::string> dirs = search_dirs ? *search_dirs : PluginHost().searchPaths();
			loadObservationLibraries(arg_.getValue(), dirs);
			loadObservationLibraries(declared, dirs);
		}
		catch (const std::exception& e)
		{
			return fail(program, e.what());
		}
		return std::nullopt;
	}
	const std::vector<std::string>& values() const { return arg_.getValue(); }

 private:
	mutable TCLAP::MultiArg<std::string> arg_;  // TCLAP's getValue() is not const
};
}  // namespace auvnav::cli
