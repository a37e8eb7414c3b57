// The digest verification by redundancy compares (core/pipeline/scheduler.h): two results of
// one task are the same bytes exactly when their digests are equal.
#ifndef PDSM_CORE_PIPELINE_RESULT_DIGEST_H_
#define PDSM_CORE_PIPELINE_RESULT_DIGEST_H_

#include <string>
#include <vector>

#include "core/events/event.h"

namespace pdsm {

// Lowercase hex SHA-256 of a task's result: every tile's index and rectangle, its per-pixel
// offsets and its events (depth as its float's bits, count), in order, little-endian, each
// list preceded by its length so that no two results share an encoding. A cryptographic hash,
// so that a worker cannot forge a different result with the digest of the right one.
// Pure; thread-safe.
std::string ResultDigest(const std::vector<TileEvents>& result);

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_RESULT_DIGEST_H_
