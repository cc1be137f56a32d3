#include "dpc/scenario_io/scenario_file.h"

#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "dpc/config/scenario_validation.h"
#include "dpc/scenario_io/scenario_reader.h"
#include "dpc/scenario_io/scenario_writer.h"
#include "support/scenario_texts.h"

namespace dpc {
namespace {

namespace pb = google::protobuf;
using ::testing::HasSubstr;
using namespace dpc::testing;

class ScenarioFileTest : public ::testing::Test {
 protected:
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
  void Write(const std::string& text) {
    std::ofstream file(path_, std::ios::binary);
    file << text;
  }
  std::optional<ScenarioError> LoadError() const {
    try {
      LoadScenarioFile(path_);
    } catch (const ScenarioError& e) {
      return e;
    }
    return std::nullopt;
  }

  // Unique per process: several worktrees may run the suite at once.
  const std::string path_ =
      fmt::format("{}scenario_text_test_{}.pbtxt", ::testing::TempDir(), ::getpid());
};

TEST_F(ScenarioFileTest, LoadsAndValidates) {
  Write(ScenarioToText(PaperScenario("131")));
  const ScenarioConfig config = LoadScenarioFile(path_);
  ExpectSameScenario(config, PaperScenario("131"));
}

TEST_F(ScenarioFileTest, MissingFileIsLocatedAtThePath) {
  const auto error = LoadError();
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), path_);
}

TEST_F(ScenarioFileTest, DirectoryIsRejected) {
  EXPECT_THROW(LoadScenarioFile(::testing::TempDir()), ScenarioError);
}

TEST_F(ScenarioFileTest, AFifoIsRefusedWithoutBlocking) {
  // Opening a FIFO for reading blocks until a writer comes; a service reading one at start-up
  // would hang and ignore SIGTERM.
  ASSERT_EQ(::mkfifo(path_.c_str(), 0600), 0);
  const auto error = LoadError();
  ::unlink(path_.c_str());
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), path_);
  EXPECT_THAT(error->message(), HasSubstr("not a regular file"));
}

TEST_F(ScenarioFileTest, OversizedFileIsLocatedAtThePath) {
  Write(std::string(kMaxScenarioTextBytes + 1, '\n'));
  const auto error = LoadError();
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), path_);
  EXPECT_THAT(error->message(), HasSubstr("16 MiB"));
}

TEST_F(ScenarioFileTest, ParseErrorIsLocatedInTheFile) {
  Write("stages { axis: S1 }\ncontroller { method: FOO }\n");
  const auto error = LoadError();
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), path_ + ":2:26");  // just after FOO
}

TEST_F(ScenarioFileTest, InvalidValueIsLocatedByField) {
  Write("stages { axis: S1 }\ncontroller { step: -0.1 }\n");
  const auto error = LoadError();
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "controller.step");
}

TEST_F(ScenarioFileTest, StagelessFileIsRejected) {
  Write("name: \"nothing\"\n");
  const auto error = LoadError();
  ASSERT_TRUE(error);
  EXPECT_EQ(error->location(), "stages");
}

// ---------------------------------------------------------------------------------------------
// A non-finite value in any double field is reported at that field's path. Driven by
// reflection over scenario.proto, so that a double field added to the schema without
// validation (or without a value in the example texts) fails here.

/// One step of a field path: a field, and an element index for repeated fields (−1 otherwise).
struct PathStep {
  const pb::FieldDescriptor* field;
  int index;
};
using FieldPath = std::vector<PathStep>;

std::string PathText(const FieldPath& path) {
  std::string text;
  for (const PathStep& step : path) {
    if (!text.empty()) text += '.';
    text += step.field->name();
    if (step.index >= 0) text += fmt::format("[{}]", step.index);
  }
  return text;
}

/// Every double value present in `message` (ListFields: set fields, non-empty repeated ones),
/// recursively.
void CollectPresentDoubles(const pb::Message& message, FieldPath* prefix,
                           std::vector<FieldPath>* out) {
  const pb::Reflection* reflection = message.GetReflection();
  std::vector<const pb::FieldDescriptor*> fields;
  reflection->ListFields(message, &fields);
  for (const pb::FieldDescriptor* field : fields) {
    const int count = field->is_repeated() ? reflection->FieldSize(message, field) : 1;
    for (int i = 0; i < count; ++i) {
      prefix->push_back({field, field->is_repeated() ? i : -1});
      if (field->cpp_type() == pb::FieldDescriptor::CPPTYPE_DOUBLE) {
        out->push_back(*prefix);
      } else if (field->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE) {
        CollectPresentDoubles(field->is_repeated()
                                  ? reflection->GetRepeatedMessage(message, field, i)
                                  : reflection->GetMessage(message, field),
                              prefix, out);
      }
      prefix->pop_back();
    }
  }
}

void SetDoubleAt(pb::Message* message, const FieldPath& path, double value) {
  for (size_t k = 0; k + 1 < path.size(); ++k) {
    const pb::Reflection* reflection = message->GetReflection();
    message = path[k].index >= 0
                  ? reflection->MutableRepeatedMessage(message, path[k].field, path[k].index)
                  : reflection->MutableMessage(message, path[k].field);
  }
  const PathStep& last = path.back();
  if (last.index >= 0) {
    message->GetReflection()->SetRepeatedDouble(message, last.field, last.index, value);
  } else {
    message->GetReflection()->SetDouble(message, last.field, value);
  }
}

/// The full names of every double field reachable from `descriptor`.
void CollectSchemaDoubles(const pb::Descriptor* descriptor, std::set<const pb::Descriptor*>* seen,
                          std::set<std::string>* out) {
  if (!seen->insert(descriptor).second) return;
  for (int i = 0; i < descriptor->field_count(); ++i) {
    const pb::FieldDescriptor* field = descriptor->field(i);
    if (field->cpp_type() == pb::FieldDescriptor::CPPTYPE_DOUBLE) out->insert(field->full_name());
    if (field->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE) {
      CollectSchemaDoubles(field->message_type(), seen, out);
    }
  }
}

TEST(ScenarioFileNonFiniteTest, EveryDoubleFieldIsValidatedAtItsPath) {
  std::set<std::string> covered;
  int cases = 0;
  for (const char* text : {kFixedAxisText, kAdjustableAxisText, kInstrumentsText, kConditionTablesText}) {
    const scenario::Scenario valid = ParseScenarioText(text, "test.pbtxt");
    ASSERT_NO_THROW(ValidateScenario(ScenarioFromProto(valid)));
    std::vector<FieldPath> doubles;
    FieldPath prefix;
    CollectPresentDoubles(valid, &prefix, &doubles);
    for (const FieldPath& path : doubles) {
      covered.insert(path.back().field->full_name());
      for (double bad : {std::numeric_limits<double>::quiet_NaN(),
                         std::numeric_limits<double>::infinity(),
                         -std::numeric_limits<double>::infinity()}) {
        scenario::Scenario broken = valid;
        SetDoubleAt(&broken, path, bad);
        const std::string expected = PathText(path);
        SCOPED_TRACE(expected + " = " + std::to_string(bad));
        ++cases;
        try {
          ValidateScenario(ScenarioFromProto(broken));
          ADD_FAILURE() << "accepted";
        } catch (const ScenarioError& e) {
          EXPECT_EQ(e.location(), expected) << e.what();
        }
      }
    }
  }
  EXPECT_GT(cases, 100);

  std::set<std::string> schema;
  std::set<const pb::Descriptor*> seen;
  CollectSchemaDoubles(scenario::Scenario::descriptor(), &seen, &schema);
  EXPECT_EQ(covered, schema) << "every double field of scenario.proto needs a non-zero value in "
                                "one of the example texts (and validation)";
  EXPECT_GE(schema.size(), 36u);  // as of writing; more is fine
}

}  // namespace
}  // namespace dpc
