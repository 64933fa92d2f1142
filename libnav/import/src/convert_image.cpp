// The image converter: an image file per record (and camera parameters)
// into mrpt::obs::CObservationImage.
#include <mrpt/obs/CObservationImage.h>

#include <algorithm>
#include <cmath>

#include "converter_support.h"
#include "sensor_converters.h"

namespace auvnav::import::detail
{
namespace
{
constexpr double kMaxImageSide = 1 << 20;  // pixels; far beyond any camera or sonar image

class ImageConverter final : public MountedConverter
{
 public:
	ImageConverter(const config::Node& q, const config::Node& s, const std::string& label,
	               const std::string& data_dir)
	    : MountedConverter(s, label), data_dir_(data_dir)
	{
		file_ = parseText(q, "file");
		if (!file_.present || file_.is_constant)
			q.fail("file", "expected {field: NAME} (image file per record)");
		if (q.has("camera"))
		{
			const config::Node c = q.child("camera");
			c.allowOnly({"ncols", "nrows", "fx", "fy", "cx", "cy", "name"});
			const char* keys[6] = {"ncols", "nrows", "fx", "fy", "cx", "cy"};
			for (int i = 0; i < 6; ++i) camera_[i] = parseScalar(c, keys[i], UnitKind::Dimensionless);
			camera_name_ = parseText(c, "name");
			has_camera_ = true;
		}
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		auto o = mrpt::obs::CObservationImage::Create();
		if (!labelAndMount(*o, r, why)) return nullptr;
		std::string file;
		if (!readText(file_, r, cols_, file, why)) return nullptr;
		const std::string path = (!file.empty() && file[0] == '/') ? file : data_dir_ + "/" + file;
		// -1: as stored (colour stays colour; 0 would force grayscale). OpenCV may
		// throw on a damaged or empty file: that is this record's rejection.
		bool loaded = false;
		std::string detail;
		try
		{
			loaded = o->image.loadFromFile(path, -1);
		}
		catch (const std::exception& e)
		{
			detail = e.what();
			detail = ": " + detail.substr(0, std::min(detail.find('\n'), std::size_t{200}));
		}
		if (!loaded)
		{
			why = "cannot read image '" + path + "'" + detail;
			return nullptr;
		}
		if (has_camera_)
		{
			double v[6];
			for (int i = 0; i < 6; ++i)
				if (readScalar(camera_[i], r, cols_, v[i], why) != Read::Ok || !std::isfinite(v[i]))
				{
					if (why.empty()) why = "camera parameter missing";
					return nullptr;
				}
			// Casting a negative or huge double to uint32 is undefined behaviour.
			for (int i = 0; i < 2; ++i)
				if (!(v[i] >= 0 && v[i] <= kMaxImageSide) || std::floor(v[i]) != v[i])
				{
					why = std::string("camera ") + (i == 0 ? "ncols" : "nrows") + " " + std::to_string(v[i]) +
					      " is not an integer in 0.." + std::to_string(static_cast<long>(kMaxImageSide));
					return nullptr;
				}
			auto& cam = o->cameraParams;
			cam.ncols = static_cast<uint32_t>(v[0]);
			cam.nrows = static_cast<uint32_t>(v[1]);
			cam.intrinsicParams.setZero();
			cam.fx(v[2]);
			cam.fy(v[3]);
			cam.cx(v[4]);
			cam.cy(v[5]);
			cam.intrinsicParams(2, 2) = 1.0;
			cam.dist.fill(0);
			// An empty name is a name (MRPT's default is ""): the export writes it as an empty cell.
			if (camera_name_.present && !readText(camera_name_, r, cols_, cam.cameraName, why, true))
				return nullptr;
		}
		return o;
	}

 private:
	std::string data_dir_;
	TextSpec file_, camera_name_;
	bool has_camera_ = false;
	ScalarSpec camera_[6];
};
}  // namespace

std::unique_ptr<Converter> makeImageConverter(const config::Node& q, const config::Node& s,
                                              const std::string& label, const std::string& data_dir)
{
	return std::make_unique<ImageConverter>(q, s, label, data_dir);
}

}  // namespace auvnav::import::detail
