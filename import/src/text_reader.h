// Private: sluice's own readers for text particle files.
//
// CSV: a header row names the columns. Positions come from columns x, y, z
// (any case) or ParaView's Points:0, Points:1, Points:2. ParaView writes a
// vector array as name:0, name:1, ...; such columns form one array `name`
// (read as its magnitude). Other columns are arrays. Comma separated, or tab
// separated when the header has no comma.
//
// XYZ (.xyz, .txt): whitespace separated numbers, no header, `#` starts a
// comment. Columns 1-3 are x y z; further columns are arrays named col4,
// col5, ...; every data line has the same number of columns.
//
// Both return raw values: non-finite numbers are kept for the caller to
// repair. Errors are io::Error naming the file and line.
#pragma once

#include <string>
#include <vector>

#include "sluice/io/types.h"

namespace sluice::import::detail {

// The arrays a file offers (position columns excluded), from its first lines.
std::vector<std::string> csv_arrays(const std::string& path);
std::vector<std::string> xyz_arrays(const std::string& path);

// Reads every row. `attributes` are array names as listed by *_arrays;
// `id_array` is empty when no ids are wanted.
io::ParticleFrame read_csv(const std::string& path, const std::vector<std::string>& attributes,
                       const std::string& id_array);
io::ParticleFrame read_xyz(const std::string& path, const std::vector<std::string>& attributes,
                       const std::string& id_array);

}  // namespace sluice::import::detail
