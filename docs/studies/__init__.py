"""The studies of docs/studies.md: guided searches against unguided ones, and a stability map."""
