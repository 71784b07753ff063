"""SQLite storage (SQLAlchemy): samples and labels, command log, training runs, users."""
