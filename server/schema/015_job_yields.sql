-- Migration 15: how often a job gave its lease back at a checkpoint because it had run longer
-- than the coordinator's --yield-after while other jobs waited (docs/service.md, "Long runs
-- yield"). A lease takes the queued job that yielded fewest times first, so a campaign's short
-- runs finish before its long ones take the workers; the index orders by it first.
ALTER TABLE jobs ADD COLUMN yields INTEGER NOT NULL DEFAULT 0;
DROP INDEX jobs_queue;
CREATE INDEX jobs_queue ON jobs (state, yields, campaign_id, kind, wait_ended DESC, run_order);
