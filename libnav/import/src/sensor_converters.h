#pragma once
// Internal to the converters: one factory per observation class, each defined
// in its convert_<class>.cpp; makeConverter (converters.cpp) picks one.
#include <auvnav/config.h>

#include <memory>
#include <string>

#include "converters.h"

namespace auvnav::import::detail
{
/** What makeConverter calls to build the converter of one class. */
using ConverterFactory = std::unique_ptr<Converter> (*)(const config::Node& q, const config::Node& s,
                                                        const std::string& label);

/** The factory of converter class `C` (constructible from q, s, label).
 *  Each convert_<class>.cpp defines its entry below with it. */
template <class C>
std::unique_ptr<Converter> factoryOf(const config::Node& q, const config::Node& s, const std::string& label)
{
	return std::make_unique<C>(q, s, label);
}

extern const ConverterFactory makeImuConverter;
extern const ConverterFactory makeDvlConverter;
extern const ConverterFactory makePressureConverter;
extern const ConverterFactory makeGpsConverter;
extern const ConverterFactory makeAdcpConverter;
extern const ConverterFactory makeThrustersConverter;
extern const ConverterFactory makeUsblConverter;
/** `data_dir` resolves relative image paths. */
std::unique_ptr<Converter> makeImageConverter(const config::Node& q, const config::Node& s,
                                              const std::string& label, const std::string& data_dir);

}  // namespace auvnav::import::detail
