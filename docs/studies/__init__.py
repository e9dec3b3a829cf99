"""The studies of docs/evidence-studies.md: guided searches against unguided ones, and a stability map."""
