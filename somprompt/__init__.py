"""Set-of-Mark prompting from label maps (temporary init, completed below)."""
