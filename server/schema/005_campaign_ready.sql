-- Migration 5: a campaign's jobs are inserted in batches, each in its own short transaction; the
-- campaign is invisible (ready = 0) until the last batch is in.
      ALTER TABLE campaigns ADD COLUMN ready INTEGER NOT NULL DEFAULT 1;
