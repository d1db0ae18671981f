// CF time units and calendars.
#include "cf_time.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <regex>

#include "import_error.hpp"

namespace cv::importers {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool gregorian_leap(int y) { return (y % 4 == 0 && y % 100 != 0) || y % 400 == 0; }

int month_days(Calendar cal, int y, int m) {
  static const int days[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  if (cal == Calendar::Day360) return 30;
  if (m == 2) {
    if (cal == Calendar::AllLeap) return 29;
    if (cal == Calendar::NoLeap) return 28;
    return gregorian_leap(y) ? 29 : 28;
  }
  return days[m - 1];
}

int year_days(Calendar cal, int y) {
  switch (cal) {
    case Calendar::Day360: return 360;
    case Calendar::NoLeap: return 365;
    case Calendar::AllLeap: return 366;
    default: return gregorian_leap(y) ? 366 : 365;
  }
}

// Adds whole days to a date in the given calendar.
void add_days(Calendar cal, int& y, int& m, int& d, std::int64_t n) {
  if (cal == Calendar::Gregorian) {
    std::int64_t z = days_from_civil(y, m, d) + n;
    // Inverse of days_from_civil (era-based, proleptic Gregorian).
    z += 719468;
    const std::int64_t era = (z >= 0 ? z : z - 146096) / 146097;
    const std::int64_t doe = z - era * 146097;
    const std::int64_t yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
    const std::int64_t doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    const std::int64_t mp = (5 * doy + 2) / 153;
    d = static_cast<int>(doy - (153 * mp + 2) / 5 + 1);
    m = static_cast<int>(mp < 10 ? mp + 3 : mp - 9);
    y = static_cast<int>(yoe + era * 400 + (m <= 2));
    return;
  }
  // Fixed-length-year calendars: walk years, then months.
  std::int64_t doy = d - 1;
  for (int mm = 1; mm < m; ++mm) doy += month_days(cal, y, mm);
  doy += n;
  const int yd = year_days(cal, y);
  std::int64_t years = doy >= 0 ? doy / yd : -((-doy + yd - 1) / yd);
  y += static_cast<int>(years);
  doy -= years * yd;
  m = 1;
  while (doy >= month_days(cal, y, m)) doy -= month_days(cal, y, m++);
  d = static_cast<int>(doy) + 1;
}
}  // namespace

std::int64_t days_from_civil(int y, int m, int d) {
  y -= m <= 2;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const std::int64_t yoe = y - era * 400;
  const std::int64_t doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const std::int64_t doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + doe - 719468;
}

TimeUnits parse_time_units(const std::string& units, const std::string& calendar, const std::string& where) {
  static const std::regex re(
      R"(^\s*([A-Za-z]+)\s+since\s+(-?\d{1,4})-(\d{1,2})-(\d{1,2})(?:[T ]+(\d{1,2}):(\d{1,2})(?::(\d{1,2}(?:\.\d*)?))?)?\s*(Z|UTC|GMT|[+-]\d{1,2}(?::?\d{2})?)?\s*$)",
      std::regex::icase);
  std::smatch m;
  if (!std::regex_match(units, m, re)) {
    throw ImportError(where + ": time units '" + units + "', expected '<unit> since YYYY-MM-DD[ hh:mm:ss][Z]'");
  }
  TimeUnits u;
  const std::string unit = lower(m[1]);
  if (unit == "s" || unit == "sec" || unit == "secs" || unit == "second" || unit == "seconds") u.seconds_per_unit = 1;
  else if (unit == "min" || unit == "mins" || unit == "minute" || unit == "minutes") u.seconds_per_unit = 60;
  else if (unit == "h" || unit == "hr" || unit == "hrs" || unit == "hour" || unit == "hours") u.seconds_per_unit = 3600;
  else if (unit == "d" || unit == "day" || unit == "days") u.seconds_per_unit = 86400;
  else throw ImportError(where + ": time unit '" + m[1].str() + "', expected seconds, minutes, hours or days");
  u.year = std::stoi(m[2]);
  u.month = std::stoi(m[3]);
  u.day = std::stoi(m[4]);
  if (m[5].matched) u.hour = std::stoi(m[5]);
  if (m[6].matched) u.minute = std::stoi(m[6]);
  if (m[7].matched) u.second = std::stod(m[7]);
  if (m[8].matched) {
    const std::string tz = m[8];
    if (tz[0] == '+' || tz[0] == '-') {
      const std::string digits = std::regex_replace(tz.substr(1), std::regex(":"), "");
      const int hh = std::stoi(digits.substr(0, digits.size() > 2 ? digits.size() - 2 : digits.size()));
      const int mm = digits.size() > 2 ? std::stoi(digits.substr(digits.size() - 2)) : 0;
      u.utc_offset_s = (tz[0] == '-' ? -1 : 1) * (hh * 3600.0 + mm * 60.0);
    }
  }
  const std::string cal = lower(calendar);
  if (cal.empty() || cal == "standard" || cal == "gregorian" || cal == "proleptic_gregorian") u.calendar = Calendar::Gregorian;
  else if (cal == "noleap" || cal == "365_day") u.calendar = Calendar::NoLeap;
  else if (cal == "all_leap" || cal == "366_day") u.calendar = Calendar::AllLeap;
  else if (cal == "360_day") u.calendar = Calendar::Day360;
  else {
    throw ImportError(where + ": calendar '" + calendar +
                      "', expected standard, gregorian, proleptic_gregorian, noleap, 365_day, all_leap, 366_day or 360_day");
  }
  if (u.month < 1 || u.month > 12 || u.day < 1 || u.day > month_days(u.calendar, u.year, u.month) || u.hour > 24 ||
      u.minute > 59 || u.second >= 61) {
    throw ImportError(where + ": time units '" + units + "' hold an impossible reference date, expected a real date and time of day");
  }
  return u;
}

core::ValidTime valid_time(const TimeUnits& u, double value, bool* approximated) {
  // Beyond +-10 000 years from the reference the date arithmetic would overflow: no file means that.
  if (!std::isfinite(value) || std::abs(value * u.seconds_per_unit) > 3.2e11) {
    throw ImportError("time value " + std::to_string(value) + " is not within 10 000 years of the reference date");
  }
  // Offset from the reference instant in whole days plus seconds of day, exact to the second for
  // any value a file can hold.
  const double total_s = value * u.seconds_per_unit + u.hour * 3600.0 + u.minute * 60.0 + u.second - u.utc_offset_s;
  const double day_s = std::floor(total_s / 86400.0);
  double sod = std::round(total_s - day_s * 86400.0);
  std::int64_t days = static_cast<std::int64_t>(day_s);
  if (sod >= 86400.0) {
    sod -= 86400.0;
    ++days;
  }
  int y = u.year, m = u.month, d = u.day;
  add_days(u.calendar, y, m, d, days);
  const int isod = static_cast<int>(sod);
  char buf[48];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02dZ", y, m, d, isod / 3600, (isod / 60) % 60, isod % 60);
  core::ValidTime t;
  t.iso_utc = buf;
  const int real_d = std::min(d, month_days(Calendar::Gregorian, y, m));
  if (approximated) *approximated = real_d != d || u.calendar != Calendar::Gregorian;
  t.unix_s = days_from_civil(y, m, real_d) * 86400 + isod;
  return t;
}

}  // namespace cv::importers
