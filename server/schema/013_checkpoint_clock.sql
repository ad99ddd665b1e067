-- Migration 13: the run's clock at a job's latest checkpoint, as its worker sent it: the
-- simulated seconds and steps of the state it holds, since the run's start (0 for a checkpoint
-- kept before, or sent without them).
ALTER TABLE checkpoints ADD COLUMN simulated_seconds REAL NOT NULL DEFAULT 0;
ALTER TABLE checkpoints ADD COLUMN steps INTEGER NOT NULL DEFAULT 0;
