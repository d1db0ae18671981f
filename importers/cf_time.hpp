// CF time coordinates: "<unit> since <date>" in any of the spellings real files use, and the CF
// calendars (standard, proleptic_gregorian, noleap/365_day, all_leap/366_day, 360_day).
#pragma once

#include <cstdint>
#include <string>

#include "volume/cloud_volume.hpp"

namespace cv::importers {

enum class Calendar { Gregorian, NoLeap, AllLeap, Day360 };

struct TimeUnits {
  double seconds_per_unit = 3600.0;
  int year = 1970, month = 1, day = 1, hour = 0, minute = 0;
  double second = 0.0;
  double utc_offset_s = 0.0;  // the reference date's time zone (subtracted)
  Calendar calendar = Calendar::Gregorian;
};

// Parses units (and the calendar attribute, "" meaning standard). Throws ImportError naming `where`
// with what was found and what was expected.
TimeUnits parse_time_units(const std::string& units, const std::string& calendar, const std::string& where);

// The valid time of a coordinate value. For calendars other than Gregorian the date is kept in the
// file's calendar in iso_utc; unix_s is that date clamped into a real one (30 February -> 28/29
// February) and `approximated` says so.
core::ValidTime valid_time(const TimeUnits& u, double value, bool* approximated = nullptr);

// Days from 1970-01-01 to a proleptic Gregorian date.
std::int64_t days_from_civil(int y, int m, int d);

}  // namespace cv::importers
