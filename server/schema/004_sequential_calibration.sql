-- Migration 4: the sequential calibration: its rounds, its stage boxes, and the jobs of its stage
-- designs (kind 'stage:<n>'), which need the jobs table rebuilt as in migration 2.
      CREATE TABLE jobs_v4 (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        campaign_id INTEGER NOT NULL REFERENCES campaigns(id),
        std_order INTEGER NOT NULL,
        run_order INTEGER NOT NULL,
        test TEXT NOT NULL,
        kind TEXT NOT NULL CHECK (kind IN ('design', 'verify') OR kind LIKE 'diagnose:%'
                                  OR kind LIKE 'stage:%'),
        payload TEXT NOT NULL,
        state TEXT NOT NULL
          CHECK (state IN ('queued', 'leased', 'done', 'failed', 'cancelled')),
        attempt INTEGER NOT NULL DEFAULT 0,
        counted INTEGER NOT NULL DEFAULT 0,
        lease_deadline REAL NOT NULL DEFAULT 0,
        worker TEXT NOT NULL DEFAULT '',
        error TEXT NOT NULL DEFAULT '',
        finished REAL NOT NULL DEFAULT 0);
      INSERT INTO jobs_v4 SELECT * FROM jobs;
      DROP TABLE jobs;
      ALTER TABLE jobs_v4 RENAME TO jobs;
      CREATE INDEX jobs_queue ON jobs (state, campaign_id, kind, run_order);
      CREATE INDEX jobs_campaign ON jobs (campaign_id);
      CREATE TABLE calibration_rounds (
        campaign_id INTEGER NOT NULL REFERENCES campaigns(id),
        round INTEGER NOT NULL,
        stage INTEGER NOT NULL,
        proposal_json TEXT NOT NULL,
        created REAL NOT NULL,
        PRIMARY KEY (campaign_id, round));
      CREATE TABLE calibration_stages (
        campaign_id INTEGER NOT NULL REFERENCES campaigns(id),
        stage INTEGER NOT NULL,
        box_json TEXT NOT NULL,
        created REAL NOT NULL,
        PRIMARY KEY (campaign_id, stage));
