#pragma once
// A fixture for the layering check's own test: a header that a core module must not have.
#include <fastdds/dds/domain/DomainParticipant.hpp>
