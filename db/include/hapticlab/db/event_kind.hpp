#pragma once
/// @file The kinds of session event (the audit trail, docs/studies.md). The event table's
/// `kind` column holds a kind's name (kEventKindNames); code passes the enum.

#include "hapticlab/core/enum_names.hpp"

namespace hapticlab::db {

enum class EventKind {
  kConsent,             ///< consent confirmed, or not applicable (simulated)
  kConsentUnconfirmed,  ///< schema v7 migration: an older consent event nobody confirmed
  kDevice,              ///< the rig the session runs on
  kSamplesPlaced,       ///< the experimenter confirmed the samples' sides before a trial
  kBreakPlanned,        ///< the plan puts a break before this trial
  kBreak,               ///< a break was taken
  kPause,               ///< console: paused
  kResume,              ///< console: resumed; or `study resume` continued the session
  kAbortRequested,      ///< the experimenter in the console (this and the next four)
  kAbortCancelled,
  kAbortConfirmed,
  kBreakRequested,
  kBreakEnded,
  kAbort,                   ///< the session stopped before its end, and why
  kInterrupted,             ///< SIGINT or SIGTERM stopped the session
  kDeviceFault,             ///< the watchdog saw the device fail; or a side touched nothing
  kTrajectoryFault,         ///< a trial's trajectories were not stored whole
  kAttemptFaulted,          ///< an attempt faulted and its trial was re-queued
  kConstraintRelaxed,       ///< a re-queued trial repeats a material
  kModeChange,              ///< the session continued in another mode (--change-mode)
  kStopped,                 ///< the session stopped on an error and was marked failed
  kModeInferred,            ///< a schema migration inferred the session's mode
  kTrajectoryUnattributed,  ///< a schema migration could not attribute trajectories
  kRenderStats,             ///< written by the first `demo` builds only; read, never written
  /// Not a kind: the value of an event nobody named. It has no name, and Database::LogEvent
  /// refuses it, so a writer that forgets `.kind` fails instead of recording a false
  /// consent (or any other) event.
  kUnnamed,
};

inline constexpr EnumTable<EventKind, 24> kEventKindNames{
    {{EventKind::kConsent, "consent"},
     {EventKind::kConsentUnconfirmed, "consent-unconfirmed"},
     {EventKind::kDevice, "device"},
     {EventKind::kSamplesPlaced, "samples-placed"},
     {EventKind::kBreakPlanned, "break-planned"},
     {EventKind::kBreak, "break"},
     {EventKind::kPause, "pause"},
     {EventKind::kResume, "resume"},
     {EventKind::kAbortRequested, "abort-requested"},
     {EventKind::kAbortCancelled, "abort-cancelled"},
     {EventKind::kAbortConfirmed, "abort-confirmed"},
     {EventKind::kBreakRequested, "break-requested"},
     {EventKind::kBreakEnded, "break-ended"},
     {EventKind::kAbort, "abort"},
     {EventKind::kInterrupted, "interrupted"},
     {EventKind::kDeviceFault, "device-fault"},
     {EventKind::kTrajectoryFault, "trajectory-fault"},
     {EventKind::kAttemptFaulted, "attempt-faulted"},
     {EventKind::kConstraintRelaxed, "constraint-relaxed"},
     {EventKind::kModeChange, "mode-change"},
     {EventKind::kStopped, "stopped"},
     {EventKind::kModeInferred, "mode-inferred"},
     {EventKind::kTrajectoryUnattributed, "trajectory-unattributed"},
     {EventKind::kRenderStats, "render-stats"}}};

}  // namespace hapticlab::db
