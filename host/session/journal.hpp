// The measurement journal of a calibration session: an append-only, crash-safe file of every
// measurement taken so far, so that `--resume` carries on after a crash, a power cut or a kill
// without losing or repeating a pose, and without mixing in measurements of another session.
//
// File format (text, one line per entry, each ending in " crc=XXXXXXXX\n": the CRC-32 of
// shared/crc32.hpp, 8 lower-case hex digits, over every byte of the line before " crc="):
//   kincal-journal=1 joints=N orientation=0|1 covariance=0|1 [pose_covariance=1] id.KEY=VALUE ... crc=...
//   pose=P seq=S time_us=T q=Q1,...,QN p=X,Y,Z [o=QW,QX,QY,QZ] [c=CXX,CXY,CXZ,CYY,CYZ,CZZ]
//     [r=CXRX,CXRY,CXRZ,CYRX,CYRY,CYRZ,CZRX,CZRY,CZRZ,CRXRX,CRXRY,CRXRZ,CRYRY,CRYRZ,CRZRZ] crc=...
// The header line records the layout every record has (joint count; orientation; covariance;
// the full pose covariance, written only when on, so journals without it read as before)
// and the session's identity: KEY=VALUE items the caller chooses (model file hash, plan hash,
// seed, options), keys of [A-Za-z0-9_.-], values percent-escaped (every byte outside '!'..'~'
// and '%' itself as %XX). Records: the plan's pose index P, the platform's measurement sequence
// number S and timestamp T (us, unwrapped by the caller), the joint readings (rad or m), the
// tool point (m), the orientation device_R_tool as a unit quaternion and the point's covariance
// (m^2, upper triangle) and the rest of the full pose's 6x6 covariance (issue #26: the
// position-rotation block row by row, then the rotation block's upper triangle, in the order and
// convention of the dataset's 15 columns, host/model/dataset.hpp; it needs the orientation and
// the covariance) -- the fields of a model::Measurement. Numbers are written in their
// shortest exact form (std::to_chars) and read back bit for bit (std::from_chars).
//
// Durability: create() writes the header to PATH.tmp, fsyncs it, links it to PATH (never
// replacing an existing file), removes PATH.tmp and fsyncs the directory, so PATH either does
// not exist or holds a complete header. append() writes one whole line with O_APPEND and fsyncs
// the file before it returns: a record append() returned from survives a crash of the process
// or the machine. A crash during append() can leave at most the last line torn. The file is
// held under an exclusive flock() while the Journal is open, so two processes never write it.
//
// Resume: resume() reads every line and checks its CRC and syntax. The last line is allowed to
// be torn (no newline, bad CRC, unparsable): it is cut off the file (ftruncate + fsync) and a
// note says so. Anything wrong on an earlier line is an error naming the line: data is never
// dropped silently. A pose index recorded twice is an error naming both lines.
//
// Reading: resume() reads through files::read_text_from() (files/input_file.hpp): a regular file
// (a directory, a device, a named pipe are refused by name before they are opened) of at most
// files::kJournalFile.max_bytes, its bytes as they are (the CRCs check them).
//
// Cost: append() is one write() and one fsync() (milliseconds on a disk, dominated by the
// fsync); resume() reads the whole file, O(bytes). Memory: every record is kept in memory.
// Not thread-safe: one Journal object per thread.
//
// Errors: JournalError (a model::InputError), its message "PATH[:LINE]: what" -- the file exists
// (create) or does not (resume); another process holds it; the header is missing, torn or not a
// journal; the identity or layout differs from the caller's (every differing item named, with
// its value in the journal and now); a bad line before the last; a duplicate pose index; a
// record that does not fit the layout or has a non-finite number, a quaternion that is not
// unit (1e-3) or a covariance that is not positive definite (append, naming the pose), a pose
// covariance whose position block is not the record's covariance; an
// operating-system failure (with strerror). After a failed write append() cuts the partial line
// off again; if even that fails, the Journal refuses further appends.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "host/model/dataset.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::session {

class JournalError : public model::InputError {
 public:
  using model::InputError::InputError;
};

// What every record of a journal carries, and who wrote it.
struct JournalIdentity {
  int joint_count = 0;
  bool orientation = false;                  // every record has an orientation
  bool covariance = false;                   // every record has a covariance
  bool pose_covariance = false;              // every record has the full 6x6 (needs both above)
  std::map<std::string, std::string> items;  // e.g. {"model_sha256", ...}, {"plan_sha256", ...}, {"seed", "7"}
};

struct JournalRecord {
  int pose_index = 0;                  // in the plan, >= 0
  std::uint32_t sequence = 0;          // the platform's measurement sequence number
  std::uint64_t platform_time_us = 0;  // the platform's clock at the measurement, unwrapped
  std::vector<double> q;               // joint readings, rad or m
  model::Vector3 position_m = model::Vector3::Zero();
  std::optional<Eigen::Quaterniond> orientation;  // device_R_tool
  std::optional<model::Matrix3> covariance_m2;    // of position_m
  std::optional<model::Matrix6> pose_covariance;  // of (position_m, rotation), its top-left covariance_m2
  int line = 0;                                   // 1-based line in the journal (set by the Journal)
};

class Journal {
 public:
  // A new journal at `path` holding only the header. Throws JournalError if `path` exists.
  static Journal create(const std::string& path, const JournalIdentity& identity);
  // An existing journal, checked against `identity` (see above for what is checked and cut).
  static Journal resume(const std::string& path, const JournalIdentity& identity);

  Journal(Journal&& other) noexcept;
  Journal& operator=(Journal&& other) noexcept;
  Journal(const Journal&) = delete;
  Journal& operator=(const Journal&) = delete;
  ~Journal();  // closes the file (and so releases the lock)

  const std::string& path() const { return path_; }
  const JournalIdentity& identity() const { return identity_; }
  // What resume() did that the user should hear about (a torn last line cut off).
  const std::vector<std::string>& notes() const { return notes_; }
  // In the order they were appended.
  const std::vector<JournalRecord>& records() const { return records_; }
  bool done(int pose_index) const { return lines_by_pose_.count(pose_index) != 0; }

  // Validates the record against the layout, writes it and fsyncs (see above); on return it is
  // durable. Throws JournalError if the pose is already recorded or the record is bad.
  void append(const JournalRecord& record);

  // The records as a dataset in plan order (ascending pose index), whatever order they were
  // appended in: source = the journal's path, line = the record's journal line.
  model::Dataset dataset() const;
  // dataset() in the dataset CSV format (model::write_dataset): the same bytes for a resumed
  // run as for an uninterrupted one with the same measurements.
  void write_csv(std::ostream& out) const;

 private:
  Journal(std::string path, JournalIdentity identity, int fd);

  std::string path_;
  JournalIdentity identity_;
  int fd_ = -1;
  bool broken_ = false;     // a failed append could not be undone
  int lines_ = 0;           // lines in the file (the header included)
  std::int64_t bytes_ = 0;  // size of the file: where the next line starts
  std::vector<std::string> notes_;
  std::vector<JournalRecord> records_;
  std::map<int, int> lines_by_pose_;  // pose index -> journal line
};

}  // namespace kincal::session
