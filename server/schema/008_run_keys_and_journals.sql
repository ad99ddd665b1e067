-- Migration 8: run keys and the lab protocol version each was computed under (server/run_key.hpp;
-- NULL until the coordinator computes those of older jobs at opening), results taken from an
-- earlier run with the same key instead of simulated (the source job, or the journal line), and the
-- runs read from journals.
      ALTER TABLE jobs ADD COLUMN run_key TEXT;
      ALTER TABLE jobs ADD COLUMN run_protocol INTEGER NOT NULL DEFAULT 0;
      CREATE INDEX jobs_run_key ON jobs (run_key, state);
      ALTER TABLE results ADD COLUMN reused_from INTEGER NOT NULL DEFAULT 0;
      ALTER TABLE results ADD COLUMN reused_journal TEXT NOT NULL DEFAULT '';
      CREATE TABLE journal_runs (
        run_key TEXT PRIMARY KEY,
        attempt INTEGER NOT NULL,
        metrics_json TEXT NOT NULL,
        wall_seconds REAL NOT NULL,
        flags_json TEXT NOT NULL,
        cost_json TEXT NOT NULL,
        series_json TEXT NOT NULL,
        source TEXT NOT NULL,
        imported REAL NOT NULL);
