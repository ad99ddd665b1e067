-- Migration 14: what a journal run stands for besides its key: its lab test, seed and parameters
-- (the journal line's), so that a point proposed again by a calibration within a hair of a run
-- held is given that run (docs/journal.md, "A proposal at a run held"). Runs imported before
-- have none ('' and '{}'): a later import of the same line fills them.
ALTER TABLE journal_runs ADD COLUMN test TEXT NOT NULL DEFAULT '';
ALTER TABLE journal_runs ADD COLUMN seed TEXT NOT NULL DEFAULT '';
ALTER TABLE journal_runs ADD COLUMN parameters_json TEXT NOT NULL DEFAULT '{}';
CREATE INDEX journal_runs_point ON journal_runs (test, seed);
