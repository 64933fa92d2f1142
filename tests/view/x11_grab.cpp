// x11_grab: captures the root window of $DISPLAY (the whole X screen, as
// the X server holds it) to a PNG and counts the pixels of the trajectory's
// colour. Used under Xvfb to check what auvnav-view's live window shows: the
// window's own OpenGL read-back came back black there, the server's copy of
// the screen does not.
//   x11_grab OUT.png MIN_TRAJECTORY_PIXELS
// Exit 0 if at least MIN pixels are trajectory blue, 1 if not, 2 on errors.
#include <X11/Xlib.h>
#include <X11/Xutil.h>

#include <cstdio>
#include <cstdlib>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

int main(int argc, char** argv)
{
	if (argc != 3)
	{
		std::fprintf(stderr, "usage: x11_grab OUT.png MIN_TRAJECTORY_PIXELS\n");
		return 2;
	}
	Display* display = XOpenDisplay(nullptr);
	if (!display)
	{
		std::fprintf(stderr, "x11_grab: cannot open display '%s'\n",
		             std::getenv("DISPLAY") ? std::getenv("DISPLAY") : "");
		return 2;
	}
	const Window root = DefaultRootWindow(display);
	XWindowAttributes attr;
	XGetWindowAttributes(display, root, &attr);
	XImage* image = XGetImage(display, root, 0, 0, attr.width, attr.height, AllPlanes, ZPixmap);
	if (!image)
	{
		std::fprintf(stderr, "x11_grab: XGetImage failed\n");
		XCloseDisplay(display);
		return 2;
	}
	// Channel of a pixel from its mask (8 bits per channel on Xvfb's 24-bit
	// screens); the shifts once, not per pixel.
	auto shiftOf = [](unsigned long mask)
	{
		int shift = 0;
		while (mask && !(mask & 1)) mask >>= 1, ++shift;
		return shift;
	};
	const int r_shift = shiftOf(image->red_mask), g_shift = shiftOf(image->green_mask),
	          b_shift = shiftOf(image->blue_mask);
	cv::Mat bgr(attr.height, attr.width, CV_8UC3);
	std::size_t blue = 0;
	for (int y = 0; y < attr.height; ++y)
		for (int x = 0; x < attr.width; ++x)
		{
			const unsigned long p = XGetPixel(image, x, y);
			const int r = (p >> r_shift) & 0xff, g = (p >> g_shift) & 0xff, b = (p >> b_shift) & 0xff;
			bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(b, g, r);
			// Blue-dominant: the 1-pixel line is blended with the grey
			// background; nothing else in the scene (grey, brown grid, red
			// ellipsoids, yellow fixes, green truth) is.
			if (b >= 120 && b - r >= 50 && b - g >= 30) ++blue;
		}
	XDestroyImage(image);
	XCloseDisplay(display);
	if (!cv::imwrite(argv[1], bgr))
	{
		std::fprintf(stderr, "x11_grab: cannot write %s\n", argv[1]);
		return 2;
	}
	const std::size_t min_blue = std::strtoul(argv[2], nullptr, 10);
	std::printf("x11_grab: %dx%d screen, %zu trajectory pixels (at least %zu wanted)\n", attr.width,
	            attr.height, blue, min_blue);
	return blue >= min_blue ? 0 : 1;
}
