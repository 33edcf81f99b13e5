# make install, make install-lib, and the checks make test runs on both (install-check,
# install-lib-check).
.PHONY: install install-lib install-check install-lib-check

install: all
	install -d $(DESTDIR)$(PREFIX)/bin $(DESTDIR)$(PREFIX)/lib/pkgconfig $(DESTDIR)$(PREFIX)/include/lbk
	install -m 755 $(BUILD)/lbk $(DESTDIR)$(PREFIX)/bin/lbk
	install -m 644 $(BUILD)/liblbk.a $(DESTDIR)$(PREFIX)/lib/liblbk.a
	install -m 755 $(BUILD)/liblbk.so $(DESTDIR)$(PREFIX)/lib/liblbk.so.1
	ln -sf liblbk.so.1 $(DESTDIR)$(PREFIX)/lib/liblbk.so
	install -m 644 libformat/include/lbk/*.h $(DESTDIR)$(PREFIX)/include/lbk/
	sed 's|^prefix=.*|prefix=$(PREFIX)|' $(BUILD)/lbk.pc > $(DESTDIR)$(PREFIX)/lib/pkgconfig/lbk.pc
	install -m 644 $(BUILD)/liblbkbake.a $(DESTDIR)$(PREFIX)/lib/liblbkbake.a
	install -m 755 $(BUILD)/liblbkbake.so $(DESTDIR)$(PREFIX)/lib/liblbkbake.so.1
	ln -sf liblbkbake.so.1 $(DESTDIR)$(PREFIX)/lib/liblbkbake.so
	install -m 644 bake/include/lbk/*.h $(DESTDIR)$(PREFIX)/include/lbk/
	sed 's|^prefix=.*|prefix=$(PREFIX)|' $(BUILD)/lbk-bake.pc > $(DESTDIR)$(PREFIX)/lib/pkgconfig/lbk-bake.pc
	install -d $(DESTDIR)$(PREFIX)/share/lbk/profiles
	install -m 644 tools/convert/profiles/*.profile $(DESTDIR)$(PREFIX)/share/lbk/profiles/

# The install check: the libraries installed into $(BUILD)/inst, programs built against them with
# pkg-config only, linked once with the .so and once with the .a: install_check (liblbk) and
# bake_check (liblbkbake: includes only lbk/bake.h, compares with the installed lbk bake).
INST := $(abspath $(BUILD))/inst
INST_PC := PKG_CONFIG_PATH=$(INST)/lib/pkgconfig $(PKG_CONFIG)
install-check: all
	@rm -rf $(INST)
	@$(MAKE) --no-print-directory install PREFIX=$(INST) >/dev/null
	@mkdir -p $(BUILD)/tests
	$(CC) $(CSTD) $(WARN) tests/install/install_check.c -o $(BUILD)/tests/install_check_shared \
	    $$($(INST_PC) --cflags --libs lbk) -Wl,-rpath,$(INST)/lib $(CMOCKA_LIBS)
	$(CC) $(CSTD) $(WARN) tests/install/install_check.c -o $(BUILD)/tests/install_check_static \
	    $$($(INST_PC) --cflags lbk) $(INST)/lib/liblbk.a \
	    $$($(INST_PC) --static --libs-only-other --libs-only-l lbk | sed 's/-llbk//') $(CMOCKA_LIBS)
	$(CC) $(CSTD) $(WARN) -DLBK_CLI='"$(INST)/bin/lbk"' -DLBK_BAKE_PC_VERSION="\"$$($(INST_PC) --modversion lbk-bake)\"" \
	    tests/install/bake_check.c -o $(BUILD)/tests/bake_check_shared \
	    $$($(INST_PC) --cflags --libs lbk-bake) -Wl,-rpath,$(INST)/lib $(CMOCKA_LIBS)
	$(CC) $(CSTD) $(WARN) -DLBK_CLI='"$(INST)/bin/lbk"' -DLBK_BAKE_PC_VERSION="\"$$($(INST_PC) --modversion lbk-bake)\"" \
	    tests/install/bake_check.c -o $(BUILD)/tests/bake_check_static \
	    $$($(INST_PC) --cflags lbk-bake) $(INST)/lib/liblbkbake.a $(INST)/lib/liblbk.a \
	    $$($(INST_PC) --static --libs-only-other --libs-only-l lbk-bake | sed 's/-llbkbake//; s/-llbk\b//') $(CMOCKA_LIBS)

# ---- liblbk alone: zstd, xxHash and a C compiler, nothing else -----------------------------
# install-lib builds and installs only the container library (static, shared, headers, lbk.pc).
# install-lib-check installs it into a throwaway DESTDIR from a build folder of its own, checks
# that nothing but libformat was compiled and that liblbk.so needs only zstd, xxHash and libc/libm,
# and builds tests/install/install_check.c against the staged copy (run by tests/run.sh).
install-lib: $(BUILD)/liblbk.a $(BUILD)/liblbk.so $(BUILD)/lbk.pc
	install -d $(DESTDIR)$(PREFIX)/lib/pkgconfig $(DESTDIR)$(PREFIX)/include/lbk
	install -m 644 $(BUILD)/liblbk.a $(DESTDIR)$(PREFIX)/lib/liblbk.a
	install -m 755 $(BUILD)/liblbk.so $(DESTDIR)$(PREFIX)/lib/liblbk.so.1
	ln -sf liblbk.so.1 $(DESTDIR)$(PREFIX)/lib/liblbk.so
	install -m 644 libformat/include/lbk/*.h $(DESTDIR)$(PREFIX)/include/lbk/
	sed 's|^prefix=.*|prefix=$(PREFIX)|' $(BUILD)/lbk.pc > $(DESTDIR)$(PREFIX)/lib/pkgconfig/lbk.pc
LIBONLY := $(BUILD)/lib-only
LIBSTAGE := $(abspath $(LIBONLY))/stage
LIBPC = PKG_CONFIG_PATH=$(LIBSTAGE)/opt/lbk/lib/pkgconfig $(PKG_CONFIG) --define-variable=prefix=$(LIBSTAGE)/opt/lbk
install-lib-check:
	@rm -rf $(LIBSTAGE) && mkdir -p $(BUILD)/tests
	@$(MAKE) --no-print-directory install-lib BUILD=$(LIBONLY) PREFIX=/opt/lbk DESTDIR=$(LIBSTAGE) >/dev/null
	@built=$$(cd $(LIBONLY) && find . -name '*.o' ! -path './*/libformat/*'); \
	  if [ -n "$$built" ]; then echo "install-lib compiled more than libformat:" $$built; exit 1; fi
	@needed=$$(readelf -d $(LIBSTAGE)/opt/lbk/lib/liblbk.so.1 | sed -n 's/.*Shared library: \[\(.*\)\]/\1/p' | sort | tr '\n' ' '); \
	  case "$$needed" in "libc.so.6 libm.so.6 libxxhash.so.0 libzstd.so.1 ") ;; \
	  *) echo "liblbk.so needs more than zstd, xxHash, libc and libm: $$needed"; exit 1;; esac
	$(CC) $(CSTD) $(WARN) tests/install/install_check.c -o $(BUILD)/tests/install_lib_check \
	    $$($(LIBPC) --cflags lbk) $(LIBSTAGE)/opt/lbk/lib/liblbk.a \
	    $$($(LIBPC) --static --libs-only-other --libs-only-l lbk | sed 's/-llbk//') $(CMOCKA_LIBS)
