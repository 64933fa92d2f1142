#pragma once
// Internal to the converters: one factory per observation class, each defined
// in its convert_<class>.cpp; makeConverter (converters.cpp) picks one.
#include <auvnav/config.h>

#include <memory>
#include <string>

#include "converters.h"

namespace auvnav::import::detail
{
std::unique_ptr<Converter> makeImuConverter(const config::Node& q, const config::Node& s,
                                            const std::string& label);
std::unique_ptr<Converter> makeDvlConverter(const config::Node& q, const config::Node& s,
                                            const std::string& label);
std::unique_ptr<Converter> makePressureConverter(const config::Node& q, const config::Node& s,
                                                 const std::string& label);
std::unique_ptr<Converter> makeGpsConverter(const config::Node& q, const config::Node& s,
                                            const std::string& label);
std::unique_ptr<Converter> makeAdcpConverter(const config::Node& q, const config::Node& s,
                                             const std::string& label);
std::unique_ptr<Converter> makeThrustersConverter(const config::Node& q, const config::Node& s,
                                                  const std::string& label);
/** `data_dir` resolves relative image paths. */
std::unique_ptr<Converter> makeImageConverter(const config::Node& q, const config::Node& s,
                                              const std::string& label, const std::string& data_dir);
std::unique_ptr<Converter> makeUsblConverter(const config::Node& q, const config::Node& s,
                                             const std::string& label);

}  // namespace auvnav::import::detail
