; TF5200 programming manual, "M/H functions with optional additional information": M functions with additional value
; https://infosys.beckhoff.com/content/1033/tccncprogramming/15556839051.html
; adapted: the blocks that rely on m_default_outp_ax_name channel parameters (N20, N30, N60) and
; the H function part dropped, N80 in its own file (m_functions_additional_value_n80.nc), M30
; appended; the fixture channel list declares M52 M54 M63.
; expect: blocks N10 N35 N40 N50 N70 N90
N10 M52=-345
N35 P1 = 567 P2 = 345
N40 X[M54=P1]
N50 S[REV 1000 M03 M63=-789]
N70 M63=-789 M52=-P2 M54=567
N90 M30
