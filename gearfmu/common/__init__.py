"""Words and checks every layer shares."""
