; TF5200 programming manual, "Global sub-routines (Call L <string>)"
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206834699.html
; adapted: the page's "....." placeholders dropped; N250 calls ini_1.nc by its name (the page's absolute path D:\prog\ is its machine's); the called files, not shown on the page, are one block each; the empty blocks do nothing, so only the blocks that act are expected.
; expect: blocks N200 N1 N250 N2 N300
;all global subroutines
%MAIN (main program)
N100
N105
N200 L gup_1.nc  ;Direct call of a global subroutine by file name if program path is configured
N250 L ini_1.nc  ;Direct call of a global subroutine
N300 M30
; --- file gup_1.nc
N1 M17
; --- file ini_1.nc
N2 M17
