// A table described as JSON for people and scripts: sizes, the space, the
// refs-per-pixel histogram (thesis Fig. 6.20) and stencil sizes.
#pragma once

#include <string>

#include "gabarit/table_view.hpp"

namespace gabarit::host {

std::string inspect_json(const TableView& table);

}  // namespace gabarit::host
