#include <auvnav/io/rawlog.h>
#include <auvnav/rawlog_run.h>

#include <chrono>
#include <filesystem>

namespace auvnav
{
namespace
{
/** Why the log gave the navigator nothing to do, or empty if it did. */
std::string uselessLogReason(const Navigator& nav, const std::string& path, const RunSummary& s)
{
	if (s.observations == 0)
	{
		// The reader takes a cut gzip stream that yields no whole object for a clean end.
		std::error_code ec;
		const auto bytes = std::filesystem::file_size(path, ec);
		if (ec || bytes == 0) return path + ": no observations (an empty rawlog)";
		return path + ": no observations in its " + std::to_string(bytes) +
		       " bytes (an empty rawlog, or one cut short or not a rawlog)";
	}
	const SensorStats& imu = nav.imuStats();
	if (imu.accepted + imu.before_init + imu.invalid > 0) return "";
	std::string seen;
	for (const auto& [label, n] : s.labels)
		seen += (seen.empty() ? "" : ", ") + label + " " + std::to_string(n);
	return path + ": no IMU observation with label '" + imu.label + "' (imu.label) among " +
	       std::to_string(s.observations) + " observations (" + seen + ")";
}
}  // namespace

RunSummary runRawlog(Navigator& nav, const std::string& path, const RunCallbacks& callbacks)
{
	if (callbacks.on_predict) nav.on_predict = callbacks.on_predict;
	if (callbacks.on_update) nav.on_update = callbacks.on_update;
	RunSummary s;
	const auto t0 = std::chrono::steady_clock::now();
	try
	{
		io::RawlogReader reader(path);
		for (;;)
		{
			if (callbacks.stop && callbacks.stop())
			{
				s.interrupted = true;
				break;
			}
			const auto obs = reader.next();
			if (!obs) break;
			nav.process(*obs);
			++s.observations;
			++s.labels[obs->sensorLabel];
			if (callbacks.on_observation) callbacks.on_observation(nav);
		}
	}
	catch (const std::exception& e)
	{
		s.error = e.what();
		s.failure = std::current_exception();
	}
	if (s.error.empty() && !s.interrupted)
		if (std::string why = uselessLogReason(nav, path, s); !why.empty())
		{
			s.error = why;
			s.failure = std::make_exception_ptr(io::RawlogError(why));
		}
	nav.finish();
	s.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	s.data_s = nav.startTime() > 0 ? nav.time() - nav.startTime() : 0.0;
	s.stats = nav.stats();
	return s;
}

}  // namespace auvnav
