"""A random operator (issue 27): seeded sessions of valid actions drive a real console through its public API,
a checker holds the invariants on every answer and state, a shrinker reduces a failing action list."""
