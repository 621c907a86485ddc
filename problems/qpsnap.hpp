#pragma once
/// The `.qpsnap` snapshot format, versions 1 and 2 (DESIGN.md "Snapshot format", INTERFACES.md):
///   8 bytes little-endian uint64 N, N bytes UTF-8 JSON header, then a data buffer of raw
///   little-endian arrays at 8-byte aligned offsets, each with its CRC32.
/// Arrays: A.indptr A.indices A.data b x0 J.indptr J.indices J.data c (required);
///         contact.kind contact.depth contact.vertex x_ref lambda_ref (optional);
///         version 2 only: mu T.indptr T.indices T.data cT v0 and the header number h
///         (Coulomb friction, Qp::friction). A version 1 file reads as mu = 0 (no friction); the
///         writer writes version 1 whenever Qp::friction is empty.
#include "solvers/core/qp.hpp"

#include <map>
#include <string>

namespace cb {

/// Optional solution arrays stored beside the QP.
struct SnapshotExtras {
    Vec x_ref, lambda_ref;  ///< empty when absent
};

/// Reads and validates a snapshot; throws InputError("PATH: FIELD: problem") and never returns
/// half a problem. A is symmetrised exactly after the asymmetry check.
Qp read_qpsnap(const std::string& path, SnapshotExtras* extras = nullptr);

/// Test hook: called by read_qpsnap after each pass over the mapped file's arrays ("checksums",
/// "structure", "values", "A built") with the mapping's address and size, so that a test can see
/// how much of the file the reader holds mapped (the copy into A gives A's pages back).
using QpsnapPassObserver = void (*)(const char* pass, const unsigned char* mapping, std::uint64_t size);
void set_qpsnap_pass_observer(QpsnapPassObserver observer);

/// The same checks on a snapshot already in memory (`path` only names it in messages); used by
/// the fuzzer, which would otherwise spend most of its time writing files.
Qp read_qpsnap_bytes(const std::string& path, const unsigned char* bytes, std::uint64_t size,
                     SnapshotExtras* extras = nullptr);

/// Reads only the JSON header (for `info` and suites that filter by metadata).
nlohmann::json read_qpsnap_header(const std::string& path);

/// Writes atomically (temporary name in the same folder, then rename).
void write_qpsnap(const std::string& path, const Qp& qp, const SnapshotExtras* extras = nullptr);

/// The value checks of read_qpsnap on an in-memory QP, for other readers (Matrix Market):
/// sizes, finite values, sorted rows, A symmetric to within 1e-12 max|A_ij| (then symmetrised
/// exactly), positive diagonal. Throws InputError("where: field: problem").
void validate_qp(const std::string& where, Qp& qp);

/// The one rule on a QP's size shared by every reader (.qpsnap header, validate_qp): n >= 1.
/// InputError("where: n: no unknowns (n = 0): ...") otherwise; m = 0 is a valid problem.
void require_unknowns(const std::string& where, std::uint64_t n);

/// Content hash of a snapshot file (hex of a 64-bit FNV-1a over the whole file), the key of
/// the reference-solution cache.
std::string qpsnap_content_hash(const std::string& path);

}  // namespace cb
