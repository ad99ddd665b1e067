-- Migration 9: the design rows a multi-fidelity campaign runs at its high level as well (kind
-- 'design:high'), rebuilt as in migration 2.
      CREATE TABLE jobs_v9 (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        campaign_id INTEGER NOT NULL REFERENCES campaigns(id),
        std_order INTEGER NOT NULL,
        run_order INTEGER NOT NULL,
        test TEXT NOT NULL,
        kind TEXT NOT NULL CHECK (kind IN ('design', 'design:high', 'verify')
                                  OR kind LIKE 'diagnose:%' OR kind LIKE 'stage:%'),
        payload TEXT NOT NULL,
        state TEXT NOT NULL
          CHECK (state IN ('queued', 'leased', 'done', 'failed', 'cancelled')),
        attempt INTEGER NOT NULL DEFAULT 0,
        counted INTEGER NOT NULL DEFAULT 0,
        lease_deadline REAL NOT NULL DEFAULT 0,
        worker TEXT NOT NULL DEFAULT '',
        error TEXT NOT NULL DEFAULT '',
        finished REAL NOT NULL DEFAULT 0,
        run_key TEXT,
        run_protocol INTEGER NOT NULL DEFAULT 0);
      INSERT INTO jobs_v9 SELECT * FROM jobs;
      DROP TABLE jobs;
      ALTER TABLE jobs_v9 RENAME TO jobs;
      CREATE INDEX jobs_queue ON jobs (state, campaign_id, kind, run_order);
      CREATE INDEX jobs_campaign ON jobs (campaign_id);
      CREATE INDEX jobs_run_key ON jobs (run_key, state);
