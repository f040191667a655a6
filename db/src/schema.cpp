#include "schema.hpp"

#include "hapticlab/db/database.hpp"

namespace hapticlab::db::internal {
namespace {

// Every migration is append-only: a released migration is never edited, a new one is added.
constexpr const char* kMigrations[] = {
    // v1: studies, participants, sessions, trials, ratings.
    R"sql(
CREATE TABLE study (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE,
  protocol_toml TEXT NOT NULL,
  protocol_hash TEXT NOT NULL,
  seed INTEGER NOT NULL,
  created_at TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now'))
);
CREATE TABLE participant (
  id INTEGER PRIMARY KEY,
  study_id INTEGER NOT NULL REFERENCES study(id),
  code TEXT NOT NULL,
  idx INTEGER NOT NULL,
  seed INTEGER NOT NULL,
  UNIQUE (study_id, code)
);
CREATE TABLE session (
  id INTEGER PRIMARY KEY,
  participant_id INTEGER NOT NULL REFERENCES participant(id),
  started_at TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now')),
  ended_at TEXT,
  status TEXT NOT NULL DEFAULT 'running',
  software_version TEXT NOT NULL DEFAULT '',
  device TEXT NOT NULL DEFAULT '',
  calibration TEXT NOT NULL DEFAULT '',
  provenance_json TEXT NOT NULL DEFAULT '{}'
);
CREATE TABLE trial (
  id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES session(id),
  plan_index INTEGER NOT NULL,
  phase TEXT NOT NULL,
  material TEXT NOT NULL,
  comparison TEXT NOT NULL DEFAULT '',
  method TEXT NOT NULL DEFAULT '',
  repetition INTEGER NOT NULL DEFAULT 0,
  left_stimulus TEXT NOT NULL DEFAULT '',
  right_stimulus TEXT NOT NULL DEFAULT '',
  status TEXT NOT NULL DEFAULT 'planned'
    CHECK (status IN ('planned','running','completed','faulted','aborted')),
  attempts INTEGER NOT NULL DEFAULT 0,
  started_at TEXT,
  completed_at TEXT
);
CREATE INDEX trial_by_session ON trial(session_id, plan_index);
CREATE TABLE rating (
  id INTEGER PRIMARY KEY,
  trial_id INTEGER NOT NULL REFERENCES trial(id),
  criterion TEXT NOT NULL,
  score REAL NOT NULL,
  response_time_s REAL NOT NULL,
  UNIQUE (trial_id, criterion)
);
)sql",
    // v2: events and trajectory chunks.
    R"sql(
CREATE TABLE event (
  id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES session(id),
  trial_id INTEGER REFERENCES trial(id),
  kind TEXT NOT NULL,
  detail TEXT NOT NULL DEFAULT '',
  created_at TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now'))
);
CREATE TABLE trajectory_chunk (
  id INTEGER PRIMARY KEY,
  trial_id INTEGER NOT NULL REFERENCES trial(id),
  stream TEXT NOT NULL,
  start_time_s REAL NOT NULL,
  rate_hz REAL NOT NULL CHECK (rate_hz > 0),
  channels TEXT NOT NULL,
  sample_count INTEGER NOT NULL,
  samples BLOB NOT NULL
);
CREATE INDEX chunk_by_trial ON trajectory_chunk(trial_id, stream, start_time_s);
)sql",
    // v3: material models, measurements, the resolved plan stored with each session.
    R"sql(
CREATE TABLE material_model (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL,
  hash TEXT NOT NULL,
  toml TEXT NOT NULL,
  created_at TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now')),
  UNIQUE (name, hash)
);
CREATE TABLE measurement (
  id INTEGER PRIMARY KEY,
  material TEXT NOT NULL,
  hash TEXT NOT NULL,
  csv TEXT NOT NULL,
  metadata_json TEXT NOT NULL DEFAULT '{}',
  created_at TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now'))
);
ALTER TABLE session ADD COLUMN plan_json TEXT NOT NULL DEFAULT '[]';
)sql",
    // v4: trajectory chunks carry the attempt that wrote them; a completed trial names its
    // completing attempt; a per-stream sample-count check is stored at completion; the
    // one-writer lease. Repair of older files: chunks of a trial started once belong to that
    // attempt; chunks of a completed trial started more than once are its completing
    // attempt's only when every stream's chunks run forward in time in the order they were
    // written (no stream restarted, so no second attempt wrote it); all others stay
    // attempt 0 (unattributed: kept, never exported or analysed) and get an event.
    R"sql(
ALTER TABLE trajectory_chunk ADD COLUMN attempt INTEGER NOT NULL DEFAULT 0;
ALTER TABLE trial ADD COLUMN completed_attempt INTEGER;
CREATE INDEX chunk_by_attempt ON trajectory_chunk(trial_id, attempt, stream, start_time_s);
CREATE TABLE trajectory_stream (
  id INTEGER PRIMARY KEY,
  trial_id INTEGER NOT NULL REFERENCES trial(id),
  attempt INTEGER NOT NULL,
  stream TEXT NOT NULL,
  rate_hz REAL NOT NULL,
  samples_offered INTEGER NOT NULL,
  samples_dropped INTEGER NOT NULL,
  samples_written INTEGER NOT NULL,
  UNIQUE (trial_id, attempt, stream)
);
CREATE TABLE writer_lease (
  id INTEGER PRIMARY KEY CHECK (id = 1),
  pid INTEGER NOT NULL,
  host TEXT NOT NULL,
  since TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now'))
);
UPDATE trial SET completed_attempt = attempts WHERE status = 'completed';
UPDATE trajectory_chunk SET attempt = 1
  WHERE trial_id IN (SELECT id FROM trial WHERE attempts = 1);
UPDATE trajectory_chunk SET attempt = (SELECT t.attempts FROM trial t WHERE t.id = trial_id)
  WHERE attempt = 0 AND trial_id IN (
    SELECT t.id FROM trial t WHERE t.status = 'completed' AND t.attempts > 1 AND NOT EXISTS (
      SELECT 1 FROM trajectory_chunk a JOIN trajectory_chunk b
        ON b.trial_id = a.trial_id AND b.stream = a.stream AND b.id > a.id
       AND b.start_time_s <= a.start_time_s
      WHERE a.trial_id = t.id));
INSERT INTO event(session_id, trial_id, kind, detail)
  SELECT t.session_id, t.id, 'trajectory-unattributed',
         'schema v4 migration: ' || count(*) || ' trajectory chunks of this trial could not be ' ||
         'assigned to one attempt; they are kept with attempt 0 and never exported'
  FROM trial t JOIN trajectory_chunk c ON c.trial_id = t.id
  WHERE c.attempt = 0 AND t.attempts > 0 GROUP BY t.id;
)sql",
    // v5: the session's mode (device back-end, actuator, screens, who rates) and each rating's
    // source. Older sessions recorded only the device: a simulated back-end's ratings are
    // marked as the simulated observer's and the screens as off (the older schema could not
    // say whether a person rated through --ui), a hardware back-end's as the participant
    // window's (hardware always rated there); the actuator is 'unrecorded'. Each inferred
    // session gets a 'mode-inferred' event saying so.
    R"sql(
ALTER TABLE session ADD COLUMN actuator TEXT NOT NULL DEFAULT '';
ALTER TABLE session ADD COLUMN screens INTEGER NOT NULL DEFAULT 0;
ALTER TABLE session ADD COLUMN rater TEXT NOT NULL DEFAULT '';
ALTER TABLE rating ADD COLUMN source TEXT NOT NULL DEFAULT '';
UPDATE session SET actuator = 'unrecorded',
  screens = CASE WHEN device IN ('sim', 'falcon-twin') THEN 0 ELSE 1 END,
  rater = CASE WHEN device IN ('sim', 'falcon-twin') THEN 'simulated' ELSE 'window' END;
UPDATE rating SET source = (SELECT s.rater FROM trial t JOIN session s ON s.id = t.session_id
                            WHERE t.id = rating.trial_id);
INSERT INTO event(session_id, kind, detail)
  SELECT id, 'mode-inferred',
         'schema v5 migration: the session''s mode was not recorded; inferred from its device ''' ||
         device || ''': ratings ' || rater || ', screens ' ||
         CASE screens WHEN 1 THEN 'on' ELSE 'off' END || ', actuator unrecorded'
  FROM session;
)sql",
    // v6: real-time timing per trial side and loop (hapticlab/db/timing.hpp): rates,
    // lateness and tick-duration percentiles [us], the lateness histogram (sparse
    // "bin:count", 0.5 us bins), misses, overflows, underruns and what the loop thread got.
    R"sql(
CREATE TABLE side_timing (
  id INTEGER PRIMARY KEY,
  trial_id INTEGER NOT NULL REFERENCES trial(id),
  attempt INTEGER NOT NULL,
  side TEXT NOT NULL,
  loop TEXT NOT NULL CHECK (loop IN ('force', 'vibration')),
  clock TEXT NOT NULL CHECK (clock IN ('real', 'virtual')),
  rate_hz REAL NOT NULL,
  achieved_rate_hz REAL NOT NULL,
  ticks INTEGER NOT NULL,
  deadline_misses INTEGER NOT NULL,
  late_p50_us REAL NOT NULL,
  late_p99_us REAL NOT NULL,
  late_p999_us REAL NOT NULL,
  late_max_us REAL NOT NULL,
  tick_p50_us REAL NOT NULL,
  tick_p99_us REAL NOT NULL,
  tick_p999_us REAL NOT NULL,
  tick_max_us REAL NOT NULL,
  late_histogram TEXT NOT NULL,
  recording_overflows INTEGER NOT NULL,
  audio_underruns INTEGER NOT NULL,
  priority TEXT NOT NULL,
  memory_locked INTEGER NOT NULL,
  timer_slack_ns INTEGER NOT NULL,
  UNIQUE (trial_id, attempt, side, loop)
);
)sql",
    // v7: each event names who or what established the fact it states (docs/studies.md, "The
    // audit trail"): an experimenter's code, the participant, hapticlab itself, a device
    // back-end, the operating system, the simulation. Older events are marked 'unrecorded';
    // the migrations' own events as theirs. Before v7 every session with a person rating got
    // a 'consent' event "consent form signed" that nobody confirmed: it is marked so, and a
    // 'consent-unconfirmed' event says it (the record itself is not rewritten).
    R"sql(
ALTER TABLE event ADD COLUMN established_by TEXT NOT NULL DEFAULT '';
UPDATE event SET established_by = 'unrecorded (before schema v7)';
UPDATE event SET established_by = 'hapticlab:migration'
  WHERE kind IN ('mode-inferred', 'trajectory-unattributed');
UPDATE event SET established_by = 'nobody: written by hapticlab at every session start before ' ||
  'schema v7, without asking anyone'
  WHERE kind = 'consent' AND detail = 'consent form signed';
UPDATE event SET established_by = 'hapticlab:session-mode'
  WHERE kind = 'consent' AND detail = 'simulated participant';
INSERT INTO event(session_id, kind, detail, established_by)
  SELECT session_id, 'consent-unconfirmed',
         'schema v7 migration: this session''s consent event ("consent form signed") was ' ||
         'written by hapticlab without anyone confirming it; the signed form is the only ' ||
         'evidence of consent', 'hapticlab:migration'
  FROM event WHERE kind = 'consent' AND detail = 'consent form signed';
)sql",
    // v8: the protocol's identity is the SHA-256 of its canonical form
    // (protocols/canonical.hpp: parsed content, comments and formatting left out). Older
    // studies get it from their recorded text when a protocol is next checked against them
    // (SQL cannot parse TOML); until then it is empty. A participant row without a session is
    // a code reserved by `participant new`.
    R"sql(
ALTER TABLE study ADD COLUMN protocol_canonical_sha256 TEXT NOT NULL DEFAULT '';
)sql",
    // v9: the measurement table (v3) goes: nothing but a test ever wrote it (issue #34).
    R"sql(
DROP TABLE IF EXISTS measurement;
)sql",
    // v10: the site that recorded each session (a short pseudonymous code, checked like a
    // participant code; docs/replication.md "Combining sites"). Older sessions were recorded
    // at the local site: they get the default code 'L0' (kDefaultSiteCode).
    R"sql(
ALTER TABLE session ADD COLUMN site_code TEXT NOT NULL DEFAULT 'L0';
)sql",
};

static_assert(sizeof(kMigrations) / sizeof(kMigrations[0]) == kSchemaVersion,
              "one migration per schema version");

}  // namespace

int MigrationCount() { return static_cast<int>(sizeof(kMigrations) / sizeof(kMigrations[0])); }
const char* MigrationSql(int k) { return kMigrations[k - 1]; }

}  // namespace hapticlab::db::internal
