-- Migration 6: a result's curves (stress-strain, yield points, drum surface, ...), apart from the
-- results so that reading metrics never reads them.
      CREATE TABLE result_series (
        job_id INTEGER PRIMARY KEY REFERENCES results(job_id),
        series_json TEXT NOT NULL);
