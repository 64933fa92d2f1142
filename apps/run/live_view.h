#pragma once
/** @file live_view.h
 *  auvnav-run --view: an interactive MRPT 3D window showing the run so far
 *  (auvnav-view's scene), refreshed about once a second of wall time. Needs
 *  a display (DISPLAY; xvfb-run works). Keeps 1 Hz track points only.
 */
#include <auvnav/navigator.h>

#include <memory>
#include <string>

namespace auvnav::run
{
class LiveView
{
   public:
	/** Throws std::runtime_error when there is no display. */
	explicit LiveView(const std::string& title);
	~LiveView();
	void onState(const Navigator& nav);
	void onFix(const std::string& label, double t, const Measurement& m, const UpdateResult& r);
	/** Redraws if a second of wall time passed (or `force`). */
	void refresh(bool force = false);
	/** Keeps the window open: `seconds` > 0, or until a key / close when 0. */
	void hold(double seconds);

   private:
	struct Impl;
	std::unique_ptr<Impl> impl_;
};
}  // namespace auvnav::run
