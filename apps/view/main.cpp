// auvnav-view: MRPT 3D view of a navigation run.
//   auvnav-view --run DIR [--truth ground_truth.csv] [--save-scene F.3Dscene]
//               [--screenshot F.png] [--size WxH] [--no-window]
// Without --no-window (and with a display) it opens an interactive MRPT window;
// --save-scene writes a file MRPT's SceneViewer3D opens; --screenshot renders
// off screen (EGL: no display server needed, Mesa's software renderer works).
#include <auvnav/cli.h>
#include <mrpt/gui/CDisplayWindow3D.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <thread>

#include "scene.h"

int main(int argc, char** argv)
{
	TCLAP::CmdLine cmd(
	    "MRPT 3D view of an auvnav-run output folder: trajectory (blue; the smoothed one orange when "
	    "the run has smoothed_states.csv), ground truth, 2-sigma ellipsoids, "
	    "vehicle, position fixes of every fix sensor (GPS, USBL: accepted in the sensor's colour, the first "
	    "yellow, the second cyan; rejected magenta), seabed.",
	    ' ', "0.1.0");
	TCLAP::ValueArg<std::string> run("r", "run", "auvnav-run output folder (states.csv, position_fixes.csv)",
	                                 true, "", "DIR", cmd);
	TCLAP::ValueArg<std::string> truth("t", "truth", "auvnav-sim ground_truth.csv", false, "", "FILE", cmd);
	TCLAP::ValueArg<std::string> save("", "save-scene", "Write the scene (opens in SceneViewer3D)", false, "",
	                                  "FILE.3Dscene", cmd);
	TCLAP::ValueArg<std::string> shot("", "screenshot", "Render off screen into a PNG", false, "", "FILE.png",
	                                  cmd);
	TCLAP::ValueArg<std::string> size("", "size", "Screenshot size", false, "1280x800", "WxH", cmd);
	TCLAP::ValueArg<double> every("", "ellipsoid-every", "Seconds between 2-sigma ellipsoids", false, 60, "S",
	                              cmd);
	TCLAP::SwitchArg no_window("", "no-window", "Do not open the interactive window", cmd);
	TCLAP::ValueArg<double> window_s("", "window-seconds", "Close the window after S seconds (0: on a key)",
	                                 false, 0, "S", cmd);

	if (const auto code = auvnav::cli::parse(cmd, argc, argv, "auvnav-view")) return *code;
	try
	{
		auvnav::view::RunData data = auvnav::view::loadRun(run.getValue());
		if (!truth.getValue().empty()) data.truth = auvnav::view::loadTruth(truth.getValue());
		auvnav::view::SceneOptions opt;
		if (!(every.getValue() > 0)) throw std::runtime_error("--ellipsoid-every must be positive");
		opt.ellipsoid_every_s = every.getValue();
		const auto scene = auvnav::view::buildScene(data, opt);
		std::printf("auvnav-view: %zu states, %zu smoothed, %zu truth rows, %zu position fixes\n",
		            data.estimate.size(), data.smoothed.size(), data.truth.size(), data.fixes.size());
		if (!save.getValue().empty())
		{
			if (!scene->saveToFile(save.getValue()))
				throw std::runtime_error("cannot write " + save.getValue());
			std::printf("  scene: %s\n", save.getValue().c_str());
		}
		if (!shot.getValue().empty())
		{
			unsigned w = 0, h = 0;
			if (std::sscanf(size.getValue().c_str(), "%ux%u", &w, &h) != 2 || w < 16 || h < 16 || w > 8192 ||
			    h > 8192)
				throw std::runtime_error("--size '" + size.getValue() + "': expected WxH, e.g. 1280x800");
			auvnav::view::renderToPng(*scene, shot.getValue(), w, h);
			std::printf("  screenshot: %s\n", shot.getValue().c_str());
		}
		if (!no_window.getValue())
		{
			if (!std::getenv("DISPLAY"))
				throw std::runtime_error(
				    "no DISPLAY for the interactive window (use --no-window, or xvfb-run)");
			mrpt::gui::CDisplayWindow3D win("auvnav-view: " + run.getValue(), 1280, 800);
			win.get3DSceneAndLock() = scene;
			win.unlockAccess3DScene();
			auvnav::view::frameWindowLikeScene(win, *scene);
			win.forceRepaint();
			if (window_s.getValue() > 0)
			{
				const auto until =
				    std::chrono::steady_clock::now() + std::chrono::duration<double>(window_s.getValue());
				while (win.isOpen() && std::chrono::steady_clock::now() < until)
				{
					win.forceRepaint();
					std::this_thread::sleep_for(std::chrono::milliseconds(100));
				}
				std::printf("  window shown for %.1f s\n", window_s.getValue());
			}
			else
			{
				std::printf("  close the window or press a key in it to quit\n");
				win.waitForKey();
			}
		}
	}
	catch (const std::exception& e)
	{
		return auvnav::cli::fail("auvnav-view", e.what());
	}
	return auvnav::cli::kExitOk;
}
