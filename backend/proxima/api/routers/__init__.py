"""One router per resource; `ALL` is the order they are mounted in."""
