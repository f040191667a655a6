#pragma once
// Generated blocks of the documentation (tests/util/test_util.cpp).

#include <string>

namespace hapticlab::test {

/// Compares the generated block `name` of a document under the source tree (the text between
/// `<!-- generated: NAME -->` and `<!-- end generated: NAME -->`) with `expected`; "" when
/// equal, else what differs. With HL_UPDATE_DOCS=1 in the environment it rewrites the block
/// instead (the generator: `HL_UPDATE_DOCS=1 build/tests/protocols_tests
/// --gtest_filter='ProtocolDocs.*'`).
std::string CheckGeneratedDocBlock(const std::string& doc_relative, const std::string& name,
                                   const std::string& expected);

}  // namespace hapticlab::test
