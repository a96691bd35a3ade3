; TF5200 programming manual, "M/H functions with optional additional information": H functions with additional value
; https://infosys.beckhoff.com/content/1033/tccncprogramming/15556839051.html
; adapted: the blocks that rely on h_default_outp_ax_name channel parameters (N120, N130, N160)
; and N180 (its text is cut off on the page) dropped, M30 appended; the fixture channel list
; declares H5 H7 H8.
; expect: blocks N110 N135 N140 N150 N170 N190
N110 H5=-345
N135 P3 = 567 P4 = -345
N140 X[H7=P3]
N150 S[REV 1500 M04 H8=-789]
N170 H8=-789 H5=P4 H7=567
N190 M30
