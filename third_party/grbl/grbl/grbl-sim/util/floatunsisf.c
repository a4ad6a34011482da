float __floatunsisf (unsigned long v) {
	return v;
}