-- Migration 11: a job may be leased after another of its campaign, kind and row (a tensile test
-- after the confined compression whose conditioned bed it starts from): jobs.waits_for names
-- that job's test; '' for none.
ALTER TABLE jobs ADD COLUMN waits_for TEXT NOT NULL DEFAULT '';
CREATE INDEX jobs_row ON jobs (campaign_id, kind, std_order, test);
