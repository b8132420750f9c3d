# Installing like a Linux tool (cmake/dfp_install.cmake, sim_host/dfp_sim/CMakeLists.txt):
#
#   make install [PREFIX=/usr/local]   dfp-sim, its man page and bash/zsh completions, the GSD
#                                      files, the Wireshark dissector and the Python client
#   make package                       the Debian package build/host/dfp21b-sim_VERSION_ARCH.deb
#                                      (CPack; Depends from dpkg-shlibdeps)
#   make test-install                  the package unpacked into an empty directory: files at
#                                      their paths, Depends, dfp-sim demo from there; then
#                                      make install into a temporary PREFIX (tests/install/)
#
# dpkg-dev brings dpkg-shlibdeps; zsh runs the zsh completion in tests/cli/test_completion.sh.
APT_PACKAGES += dpkg-dev zsh
EXTRA_TEST_TARGETS += test-install

PREFIX ?= /usr/local
INSTALL_BUILD := build/host

.PHONY: install package test-install

install: build
	cmake --install $(INSTALL_BUILD) --prefix $(PREFIX)

package: build
	cd $(INSTALL_BUILD) && cpack
	@ls $(INSTALL_BUILD)/dfp21b-sim_*.deb

test-install: package
	bash tests/install/smoke.sh $(INSTALL_BUILD) $$(ls -t $(INSTALL_BUILD)/dfp21b-sim_*.deb | head -n1)
