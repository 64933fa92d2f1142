#pragma once
/** @file cli.h
 *  Command-line parsing with uniform exit codes for the auvnav programs
 *  (header-only; needs MRPT's TCLAP, CMake target auvnav_tclap).
 *
 *  Exit codes of every program (README, "Exit codes"): 0 ok, 1 bad command
 *  line (unknown option, missing or unreadable argument), 2 bad configuration
 *  or input (the message names it); auvnav-run adds 3 (never initialised) and
 *  4 (diverged), auvnav-calibrate-mag 3 (fit refused).
 *
 *  Why: MRPT's TCLAP returns false from CmdLine::parse() both after --help /
 *  --version and after a parse error (and prints the whole usage for the
 *  latter); the programs returned 0 for both. parse() below tells them apart
 *  and reports an error as one line on stderr.
 */
#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace auvnav::cli
{
constexpr int kExitOk = 0;
constexpr int kExitUsage = 1;
constexpr int kExitBadInput = 2;

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
				missing += (missing.empty() ? "" : ", ") +
						   (a->longID().rfind('<', 0) == 0 ? a->longID() : "--" + a->getName());  // <RAWLOG> or --name
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
}  // namespace auvnav::cli
