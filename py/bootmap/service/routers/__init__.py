"""One router per resource: tableaux, their maps, recognition, axioms, health."""
