#include <auvnav/io/rawlog.h>
#include <auvnav/rawlog_run.h>

#include <chrono>

namespace auvnav
{
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
			if (callbacks.on_observation) callbacks.on_observation(nav);
		}
	}
	catch (const std::exception& e)
	{
		s.error = e.what();
		s.failure = std::current_exception();
	}
	nav.finish();
	s.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	s.data_s = nav.startTime() > 0 ? nav.time() - nav.startTime() : 0.0;
	s.stats = nav.stats();
	return s;
}

}  // namespace auvnav
