-- Migration 1: the campaigns, their jobs (kind 'design' or 'verify') and the jobs' results.
      CREATE TABLE campaigns (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        name TEXT NOT NULL,
        state TEXT NOT NULL CHECK (state IN ('running', 'done', 'cancelled')),
        spec_json TEXT NOT NULL,
        design_json TEXT NOT NULL,
        created REAL NOT NULL,
        finished REAL NOT NULL DEFAULT 0);
      CREATE TABLE jobs (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        campaign_id INTEGER NOT NULL REFERENCES campaigns(id),
        std_order INTEGER NOT NULL,
        run_order INTEGER NOT NULL,
        test TEXT NOT NULL,
        kind TEXT NOT NULL CHECK (kind IN ('design', 'verify')),
        payload TEXT NOT NULL,
        state TEXT NOT NULL
          CHECK (state IN ('queued', 'leased', 'done', 'failed', 'cancelled')),
        attempt INTEGER NOT NULL DEFAULT 0,
        counted INTEGER NOT NULL DEFAULT 0,
        lease_deadline REAL NOT NULL DEFAULT 0,
        worker TEXT NOT NULL DEFAULT '',
        error TEXT NOT NULL DEFAULT '',
        finished REAL NOT NULL DEFAULT 0);
      CREATE INDEX jobs_queue ON jobs (state, campaign_id, kind, run_order);
      CREATE INDEX jobs_campaign ON jobs (campaign_id);
      CREATE TABLE results (
        job_id INTEGER PRIMARY KEY REFERENCES jobs(id),
        attempt INTEGER NOT NULL,
        worker TEXT NOT NULL,
        metrics_json TEXT NOT NULL,
        wall_seconds REAL NOT NULL,
        stored REAL NOT NULL);
