-- Migration 2: jobs of the diagnosis (kind 'diagnose:<group>'). SQLite cannot change a CHECK in
-- place: the table is rebuilt (https://www.sqlite.org/lang_altertable.html, the 12 steps; foreign
-- keys are off while migrating).
      CREATE TABLE jobs_v2 (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        campaign_id INTEGER NOT NULL REFERENCES campaigns(id),
        std_order INTEGER NOT NULL,
        run_order INTEGER NOT NULL,
        test TEXT NOT NULL,
        kind TEXT NOT NULL CHECK (kind IN ('design', 'verify') OR kind LIKE 'diagnose:%'),
        payload TEXT NOT NULL,
        state TEXT NOT NULL
          CHECK (state IN ('queued', 'leased', 'done', 'failed', 'cancelled')),
        attempt INTEGER NOT NULL DEFAULT 0,
        counted INTEGER NOT NULL DEFAULT 0,
        lease_deadline REAL NOT NULL DEFAULT 0,
        worker TEXT NOT NULL DEFAULT '',
        error TEXT NOT NULL DEFAULT '',
        finished REAL NOT NULL DEFAULT 0);
      INSERT INTO jobs_v2 SELECT * FROM jobs;
      DROP TABLE jobs;
      ALTER TABLE jobs_v2 RENAME TO jobs;
      CREATE INDEX jobs_queue ON jobs (state, campaign_id, kind, run_order);
      CREATE INDEX jobs_campaign ON jobs (campaign_id);
