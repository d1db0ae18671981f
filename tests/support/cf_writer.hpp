// A general small CF file for importer tests: any axes, any variables, values from functions of
// the indices, so each test writes exactly the trap it reproduces.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "support/nc_builder.hpp"

namespace cv::test {

struct CfAxis {
  std::string name;
  std::vector<double> values;
  std::vector<std::pair<std::string, std::string>> atts;  // text attributes (units, standard_name, ...)
};

struct CfVar {
  std::string name;
  std::vector<std::string> dims;  // axis names, slowest first
  std::vector<std::pair<std::string, std::string>> atts;
  std::vector<std::pair<std::string, std::vector<double>>> numbers;  // numeric attributes (as int)
  // Value at the index of each of its dims (in dims order).
  std::function<double(const std::vector<int>&)> value;
};

inline void write_cf(const std::string& path, const std::vector<CfAxis>& axes, const std::vector<CfVar>& vars) {
  NcBuilder b(path);
  std::vector<int> dim_ids, var_ids;
  auto axis_of = [&](const std::string& n) {
    for (std::size_t a = 0; a < axes.size(); ++a) {
      if (axes[a].name == n) return a;
    }
    throw std::runtime_error("write_cf: no axis " + n);
  };
  for (const auto& a : axes) dim_ids.push_back(b.dim(a.name, a.values.size()));
  std::vector<int> axis_vars;
  for (std::size_t a = 0; a < axes.size(); ++a) {
    axis_vars.push_back(b.var(axes[a].name, NC_DOUBLE, {dim_ids[a]}));
    for (const auto& [k, v] : axes[a].atts) b.text(axis_vars.back(), k, v);
  }
  for (const auto& v : vars) {
    std::vector<int> d;
    for (const auto& n : v.dims) d.push_back(dim_ids[axis_of(n)]);
    var_ids.push_back(b.var(v.name, NC_DOUBLE, d));
    for (const auto& [k, t] : v.atts) b.text(var_ids.back(), k, t);
    for (const auto& [k, n] : v.numbers) b.number(var_ids.back(), k, NC_INT, n);
  }
  for (std::size_t a = 0; a < axes.size(); ++a) b.put(axis_vars[a], axes[a].values);
  for (std::size_t i = 0; i < vars.size(); ++i) {
    const auto& v = vars[i];
    std::vector<int> ext;
    for (const auto& n : v.dims) ext.push_back(static_cast<int>(axes[axis_of(n)].values.size()));
    std::size_t total = 1;
    for (int e : ext) total *= static_cast<std::size_t>(e);
    std::vector<double> data(total);
    std::vector<int> idx(ext.size(), 0);
    for (std::size_t n = 0; n < total; ++n) {
      std::size_t r = n;
      for (int a = static_cast<int>(ext.size()) - 1; a >= 0; --a) {
        idx[static_cast<std::size_t>(a)] = static_cast<int>(r % static_cast<std::size_t>(ext[static_cast<std::size_t>(a)]));
        r /= static_cast<std::size_t>(ext[static_cast<std::size_t>(a)]);
      }
      data[n] = v.value(idx);
    }
    b.put(var_ids[i], data);
  }
  b.close();
}

}  // namespace cv::test
