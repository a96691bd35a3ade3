; TF5200 programming manual, "Counting loop ($FOR)": counting loops
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206929163.html
; adapted: N90 G01 F6000 added (the loop moves X and Y without a feed); the page's N130 "..." dropped; M30 appended.
; expect: runs N110 46
; expect: runs N120 46
; expect: end X=0.642788 Y=-0.766044
N90 G01 F6000
N100 $FOR P1= 10, 100, 2  (P1 is pre-assigned the value 10 at loop start)
N110 X SIN [P1 * 5]       (within the counting loop, the NC blocks N110 to N130 are executed)
N120 Y COS [P1 * 5]
N150 $ENDFOR
N160 M30
