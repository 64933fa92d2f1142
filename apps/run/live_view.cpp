#include "live_view.h"

#include <mrpt/gui/CDisplayWindow3D.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <thread>

#include "scene.h"

// The live-view module (libauvnav_live_view.so): the only part of auvnav-run
// that links MRPT's GUI library; see live_view.h.
namespace auvnav::run
{
namespace
{
struct Impl
{
	mrpt::gui::CDisplayWindow3D window;
	view::RunData data;
	double last_t = -1e300;
	std::chrono::steady_clock::time_point last_draw{};
	bool user_camera = false;  //!< set after the final framing in hold()
	explicit Impl(const std::string& title) : window(title, 1280, 800) {}
};

class WindowLiveView final : public LiveView
{
 public:
	explicit WindowLiveView(const std::string& title) : impl_(std::make_unique<Impl>(title)) {}
	void onState(const Navigator& nav) override;
	void onFix(const std::string& label, double t, const Measurement& m, const UpdateResult& r) override;
	void refresh(bool force = false) override;
	void hold(double seconds) override;

 private:
	std::unique_ptr<Impl> impl_;
};

void WindowLiveView::onState(const Navigator& nav)
{
	if (nav.time() - impl_->last_t < 1.0) return;
	impl_->last_t = nav.time();
	view::TrackPoint p;
	p.t = nav.time();
	p.p_ned = nav.bodyPosition_n();
	p.q_nb = Eigen::Quaterniond(nav.filter().state().R_nb);
	const auto& P = nav.filter().covariance();
	p.sigma_ned = P.block<3, 3>(idx::pos, idx::pos).diagonal().cwiseMax(0.0).cwiseSqrt();
	impl_->data.estimate.push_back(p);
	refresh();
}

void WindowLiveView::onFix(const std::string& label, double t, const Measurement& m, const UpdateResult& r)
{
	if (m.z.size() < 2) return;
	impl_->data.fixes.push_back({t,
	                             label,
	                             {m.z[0], m.z[1]},
	                             r.status == UpdateStatus::Accepted || r.status == UpdateStatus::Recovered});
}

void WindowLiveView::refresh(bool force)
{
	const auto now = std::chrono::steady_clock::now();
	if (impl_->data.estimate.empty() || (!force && now - impl_->last_draw < std::chrono::seconds(1))) return;
	impl_->last_draw = now;
	auto scene = view::buildScene(impl_->data);
	impl_->window.get3DSceneAndLock() = scene;
	impl_->window.unlockAccess3DScene();
	// Follow the growing trajectory while the run lasts; the camera is the
	// user's once the run has ended (hold).
	if (!impl_->user_camera) view::frameWindowLikeScene(impl_->window, *scene);
	impl_->window.forceRepaint();
}

void WindowLiveView::hold(double seconds)
{
	refresh(true);
	impl_->user_camera = true;
	if (seconds > 0)
	{
		const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
		while (impl_->window.isOpen() && std::chrono::steady_clock::now() < until)
			std::this_thread::sleep_for(std::chrono::milliseconds(100));
		return;
	}
	std::printf("  close the 3D window or press a key in it to quit\n");
	impl_->window.waitForKey();
}

}  // namespace
}  // namespace auvnav::run

extern "C" __attribute__((visibility("default"))) auvnav::run::LiveView* auvnav_live_view_create_v1(
    const char* title, std::string* error)
{
	try
	{
		if (!std::getenv("DISPLAY"))
			throw std::runtime_error("--view needs a display (DISPLAY is not set; try xvfb-run)");
		return new auvnav::run::WindowLiveView(title ? title : "auvnav-run");
	}
	catch (const std::exception& e)
	{
		if (error) *error = e.what();
		return nullptr;
	}
}
