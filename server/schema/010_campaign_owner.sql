-- Migration 10: the token a campaign was submitted with (auth.hpp, token_name), whose unfinished
-- jobs are bounded (limits.hpp).
      ALTER TABLE campaigns ADD COLUMN owner TEXT NOT NULL DEFAULT '';
