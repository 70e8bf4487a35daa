"""Generated Lie-group maps (mechgen.codegen.lower_liegroup)."""
