-- Migration 7: the latest checkpoint of a job's simulation, from the lease that sent it; handed out
-- with the job's next lease, dropped when its result is stored.
      CREATE TABLE checkpoints (
        job_id INTEGER PRIMARY KEY REFERENCES jobs(id),
        attempt INTEGER NOT NULL,
        worker TEXT NOT NULL,
        stage TEXT NOT NULL,
        state BLOB NOT NULL,
        stored REAL NOT NULL);
