"""Standard motion-planning benchmarks run through dynfab's scenarios."""
