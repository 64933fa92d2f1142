#pragma once
/** @file live_view.h
 *  auvnav-run --view: an interactive MRPT 3D window showing the run so far
 *  (auvnav-view's scene), refreshed about once a second of wall time. Needs
 *  a display (DISPLAY; xvfb-run works). Keeps 1 Hz track points only.
 *
 *  The window lives in a separately linked module, libauvnav_live_view.so
 *  (lib/auvnav/ next to the plugins' directory), that openLiveView() loads
 *  only when --view is given: a headless run never maps MRPT's GUI stack
 *  (wxWidgets, Qt5, GLFW, GLUT, nanogui). The module is built with the program
 *  (same compiler and flags), so the interface below is a plain C++ one.
 */
#include <auvnav/navigator.h>

#include <memory>
#include <string>

namespace auvnav::run
{
class LiveView
{
 public:
	virtual ~LiveView() = default;
	virtual void onState(const Navigator& nav) = 0;
	virtual void onFix(const std::string& label, double t, const Measurement& m, const UpdateResult& r) = 0;
	/** Redraws if a second of wall time passed (or `force`). */
	virtual void refresh(bool force = false) = 0;
	/** Keeps the window open: `seconds` > 0, or until a key / close when 0. */
	virtual void hold(double seconds) = 0;
};

/** Loads the live-view module and opens its window. Throws std::runtime_error
 *  naming the module when there is no display, the module is missing or it
 *  cannot be loaded. The module stays loaded for the life of the process
 *  (unloading a GUI toolkit that started threads is not safe). */
std::unique_ptr<LiveView> openLiveView(const std::string& title);
}  // namespace auvnav::run

/** The module's entry point: a new window, or nullptr with `error` set. */
#define AUVNAV_LIVE_VIEW_ENTRY_SYMBOL "auvnav_live_view_create_v1"
extern "C" auvnav::run::LiveView* auvnav_live_view_create_v1(const char* title, std::string* error);
