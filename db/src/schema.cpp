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
};

static_assert(sizeof(kMigrations) / sizeof(kMigrations[0]) == kSchemaVersion,
              "one migration per schema version");

}  // namespace

int MigrationCount() { return static_cast<int>(sizeof(kMigrations) / sizeof(kMigrations[0])); }
const char* MigrationSql(int k) { return kMigrations[k - 1]; }

}  // namespace hapticlab::db::internal
