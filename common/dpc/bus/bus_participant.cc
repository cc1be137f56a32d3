#include "dpc/bus/bus_participant.h"

#include <cstdlib>
#include <filesystem>

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fmt/format.h>

namespace dpc::bus {
namespace fdds = eprosima::fastdds::dds;

namespace {

std::string ExecutableDirectory() {
  std::error_code error;
  const auto path = std::filesystem::read_symlink("/proc/self/exe", error);
  return error ? std::string() : path.parent_path().string();
}

}  // namespace

std::string ResolveProfilesFile() {
  if (const char* file = std::getenv(kProfilesEnvironmentVariable); file != nullptr && *file) {
    if (!std::filesystem::is_regular_file(file)) {
      throw BusError(fmt::format("{}={}: no such file", kProfilesEnvironmentVariable, file));
    }
    return file;
  }
  // The shipped loopback-only profile: installed next to the binaries, or in the source tree.
  std::vector<std::string> candidates;
  const std::string exe_dir = ExecutableDirectory();
  if (!exe_dir.empty()) candidates.push_back(exe_dir + "/../share/dpc/fastdds/loopback.xml");
#ifdef DPC_DEFAULT_PROFILES_FILE
  candidates.push_back(DPC_DEFAULT_PROFILES_FILE);
#endif
  for (const std::string& candidate : candidates) {
    if (std::filesystem::is_regular_file(candidate)) {
      return std::filesystem::weakly_canonical(candidate).string();
    }
  }
  throw BusError(fmt::format(
      "no Fast DDS profiles: set {} to an XML profiles file (see deploy/fastdds/loopback.xml)",
      kProfilesEnvironmentVariable));
}

BusParticipant::BusParticipant(const BusOptions& options) : profiles_file_(ResolveProfilesFile()) {
  if (options.domain_id < 0 || options.domain_id > 232) {
    throw BusError(fmt::format("domain {} out of range: DDS domains are 0…232", options.domain_id));
  }
  auto* factory = fdds::DomainParticipantFactory::get_instance();
  // Fast DDS reads the variable in load_profiles(); set it so that a default run uses the same
  // file we report.
  setenv(kProfilesEnvironmentVariable, profiles_file_.c_str(), 1);
  if (factory->load_profiles() != ReturnCode_t::RETCODE_OK) {
    throw BusError(fmt::format("{}: Fast DDS could not load this XML profiles file", profiles_file_));
  }
  fdds::DomainParticipantQos qos;
  if (factory->get_participant_qos_from_profile(kParticipantProfile, qos) != ReturnCode_t::RETCODE_OK) {
    throw BusError(fmt::format("{}: no participant profile \"{}\"", profiles_file_, kParticipantProfile));
  }
  qos.name(options.participant_name);
  participant_ = factory->create_participant(options.domain_id, qos);
  if (participant_ == nullptr) {
    throw BusError(fmt::format("Fast DDS could not create a participant on domain {} with {}",
                               options.domain_id, profiles_file_));
  }
  publisher_ = participant_->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
  subscriber_ = participant_->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  if (publisher_ == nullptr || subscriber_ == nullptr) {
    throw BusError("Fast DDS could not create a publisher or subscriber");
  }
}

BusParticipant::~BusParticipant() {
  if (participant_ == nullptr) return;
  // Writers and readers delete their own entities; whatever is left goes here.
  participant_->delete_contained_entities();
  fdds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

fdds::Topic* BusParticipant::TopicFor(const std::string& name, fdds::TypeSupport type) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (fdds::Topic* topic : topics_) {
    if (topic->get_name() == name) return topic;
  }
  if (type.register_type(participant_) != ReturnCode_t::RETCODE_OK &&
      participant_->find_type(type.get_type_name()).empty()) {
    throw BusError(fmt::format("could not register type {}", type.get_type_name()));
  }
  fdds::Topic* topic = participant_->create_topic(name, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  if (topic == nullptr) throw BusError(fmt::format("could not create topic {}", name));
  topics_.push_back(topic);
  return topic;
}

fdds::DataWriter* BusParticipant::CreateWriter(fdds::Topic* topic, const std::string& profile) {
  fdds::DataWriterQos qos;
  if (publisher_->get_datawriter_qos_from_profile(profile, qos) != ReturnCode_t::RETCODE_OK) {
    throw BusError(fmt::format("{}: no data_writer profile \"{}\"", profiles_file_, profile));
  }
  fdds::DataWriter* writer = publisher_->create_datawriter(topic, qos);
  if (writer == nullptr) {
    throw BusError(fmt::format("could not create a writer on {} with profile {}",
                               topic->get_name(), profile));
  }
  return writer;
}

fdds::DataReader* BusParticipant::CreateReader(fdds::Topic* topic, const std::string& profile,
                                               fdds::DataReaderListener* listener) {
  fdds::DataReaderQos qos;
  if (subscriber_->get_datareader_qos_from_profile(profile, qos) != ReturnCode_t::RETCODE_OK) {
    throw BusError(fmt::format("{}: no data_reader profile \"{}\"", profiles_file_, profile));
  }
  fdds::DataReader* reader = subscriber_->create_datareader(topic, qos, listener);
  if (reader == nullptr) {
    throw BusError(fmt::format("could not create a reader on {} with profile {}",
                               topic->get_name(), profile));
  }
  return reader;
}

}  // namespace dpc::bus
