-- Migration 3: per result, the metrics flagged as untrustworthy and the run's cost block.
      ALTER TABLE results ADD COLUMN flags_json TEXT NOT NULL DEFAULT '{}';
      ALTER TABLE results ADD COLUMN cost_json TEXT NOT NULL DEFAULT '{}';
