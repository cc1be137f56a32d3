#pragma once
// The text of idl/dpc/bench.idl, compiled in: the schema a recording stores for every bench
// topic (MCAP schema encoding "omgidl"; the type's name, e.g. "dpc::msg::StokesSample", is the
// schema's name).

#include <string_view>

namespace dpc::msg {

std::string_view BenchIdlText();

}  // namespace dpc::msg
