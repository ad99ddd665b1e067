-- Migration 12: a lease takes a job whose wait has ended before the other queued jobs of its
-- campaign and kind. jobs.wait_ended marks such a job: set, by the trigger below, when a job of
-- its campaign, kind and row whose test it waits for is done, failed or cancelled. The lease
-- then finds it first in the jobs_queue index instead of testing every waiting job in turn, a
-- cost that grew with the waiting jobs. The mark only orders: the lease still tests the wait.
ALTER TABLE jobs ADD COLUMN wait_ended INTEGER NOT NULL DEFAULT 0;
UPDATE jobs SET wait_ended = 1
  WHERE waits_for != '' AND EXISTS (
    SELECT 1 FROM jobs w WHERE w.campaign_id = jobs.campaign_id AND w.kind = jobs.kind
      AND w.std_order = jobs.std_order AND w.test = jobs.waits_for
      AND w.state IN ('done', 'failed', 'cancelled'));
DROP INDEX jobs_queue;
CREATE INDEX jobs_queue ON jobs (state, campaign_id, kind, wait_ended DESC, run_order);
CREATE TRIGGER jobs_wait_ends AFTER UPDATE OF state ON jobs
  WHEN NEW.state IN ('done', 'failed', 'cancelled')
BEGIN
  UPDATE jobs SET wait_ended = 1
    WHERE campaign_id = NEW.campaign_id AND kind = NEW.kind AND std_order = NEW.std_order
      AND waits_for = NEW.test AND wait_ended = 0;
END;
