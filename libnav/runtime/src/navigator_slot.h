#pragma once
// The navigator's private pieces shared by its source files.
#include <auvnav/filter_history.h>
#include <auvnav/navigator.h>

namespace auvnav
{
/** One sensor: its model, statistics and aiding state. */
struct Navigator::Slot
{
	SensorStats stats;
	ModelPtr model;
	double latency_s = 0;  // measurement time = stamp − latency
	SensorAiding aiding;
	std::vector<Measurement> buffer;  // prepare()'s output, reused
};

/** Brackets one sensor's work for Navigator::on_sensor_work. */
class Navigator::SensorWork
{
 public:
	SensorWork(const Navigator& nav, const std::string& label) : nav_(nav), label_(label)
	{
		if (nav_.on_sensor_work) nav_.on_sensor_work(label_, true);
	}
	~SensorWork()
	{
		if (nav_.on_sensor_work) nav_.on_sensor_work(label_, false);
	}
	SensorWork(const SensorWork&) = delete;
	SensorWork& operator=(const SensorWork&) = delete;

 private:
	const Navigator& nav_;
	const std::string& label_;
};

}  // namespace auvnav
