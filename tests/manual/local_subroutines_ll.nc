; TF5200 programming manual, "Local subroutines (Call LL <string>)"
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206828043.html
; adapted: the page's "....." placeholders and "." lines dropped (the numbered blocks stay, empty: they do nothing, so only the blocks that act are expected).
; expect: blocks N200 N9 N250 N19 N300
%L UP1           (1st local subroutine)
N1
N2
N9 M17           (M17 can also be left out)
%L UP2           (2nd local subroutine)
N11
N12
N19 M29           (M29 can also be left out)
%MAIN            (main program)
N100
N105
N200 LL UP1      (Call 1st LSUB)
N250 LL UP2      (Call 2nd LSUB)
N300 M30         (Main program end)
